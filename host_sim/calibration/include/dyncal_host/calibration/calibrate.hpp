#pragma once
// `dyncal calibrate`: excitation on a drive over Modbus, online estimators (lib/ KF and RLS with
// forgetting, sample by sample through port/linux), batch fit, table flash, before/after check.

#include <array>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "dyncal/parameter_table.hpp"
#include "dyncal_host/calibration/stream_plan.hpp"
#include "dyncal_host/diagnosis/diagnose.hpp"
#include "dyncal_host/identification/excitation/excitation.hpp"
#include "dyncal_host/identification/pipeline/identify.hpp"
#include "dyncal_host/identification/reports/prediction.hpp"
#include "dyncal_port/modbus_drive.hpp"

namespace dyncal::host {

struct CalibrateOptions {
  std::string uri = "tcp://127.0.0.1:1502";
  unsigned terms = 0;  ///< identification model (dyncal::term bits)
  double sample_rate_hz = 1000;
  double f_f = 0.1;        ///< Fourier fundamental frequency [Hz] (Eq. 27)
  int harmonics = 5;       ///< L
  int periods = 2;         ///< excitation periods streamed and identified
  int verify_periods = 1;  ///< periods of the fresh verification trajectory
  int candidates = 16;     ///< random trajectories tried; the one with the smallest cond(K) plays
  /// A designed excitation (dyncal excite) to play instead of the random candidates; f_f and
  /// harmonics are then the trajectory's own.
  std::optional<linux_port::Trajectory> excitation;
  std::uint64_t seed = 1;
  double online_cutoff_hz = 20;  ///< causal low-pass of the online path
  double rls_mu = 0.9999;
  bool flash = true;
  bool diagnose = false;  ///< run dyncal diagnose on the excitation and flash the effects found
  bool progress = true;   ///< report the runs' samples as progress (progress.hpp; shown where the program set a sink)
  bool keep_trace =
      false;             ///< keep the excitation run's torque and the batch fit's prediction (CalibrateResult::trace)
  std::string save_log;  ///< if set, the excitation log is written here as CSV (dyncal identify --data)
  /// If set, the excitation run's control law is written here (docs/cli.md "Law file": trajectory,
  /// periods, rates, the drive's PD gains, the table active during the run beside it as NAME.table),
  /// what `identify --method iv --law` needs for the saved log.
  std::string save_law;
  /// Where a run that ends in a drive fault leaves the samples recorded before it.
  std::string fault_dir = ".";
  /// Live or trace per run (stream_plan.hpp): automatic picks from the link measured before the runs.
  StreamMode stream = StreamMode::automatic;
  IdentifyOptions identify = stiction_excluded();  ///< batch fit settings (terms copied from above)

  /// Batch defaults for drive data: rows of a joint below 2 % of its top speed are left out of the
  /// fit, because the excitation reverses every joint several times per period and a joint with
  /// Coulomb friction sticks at reversals (see IdentifyOptions::min_speed_fraction); friction and
  /// rotor inertia held >= 0 (IdentifyOptions::sign_constraints), since the fit becomes the drive's
  /// table and a joint with negligible friction would otherwise come out negative half the time.
  static IdentifyOptions stiction_excluded() {
    IdentifyOptions o;
    o.min_speed_fraction = 0.02;
    o.sign_constraints = true;
    return o;
  }
};

struct VerificationErrors {
  std::array<double, modbus_map::kMaxJoints> rms{};      ///< per joint RMS of tau - K phi on the fresh trajectory [Nm]
  std::array<double, modbus_map::kMaxJoints> rms_tau{};  ///< per joint RMS of tau [Nm]
};

struct CalibrateResult {
  int num_joints = 0;    ///< the robot's; per-joint arrays are filled to here
  IdentifyResult batch;  ///< OLS fit of the excitation run, with cross-validation
  TorqueTrace trace;     ///< with CalibrateOptions::keep_trace: the excitation's torque and the batch fit's prediction
  std::vector<std::string> names;                  ///< parameter names, model order
  std::vector<double> phi_batch, phi_kf, phi_rls;  ///< batch: identify's model; KF, RLS: lib's (per joint)
  double trajectory_cond = 0;                      ///< cond(K) of the chosen excitation (Eq. 26, columns unit-scaled)
  long samples = 0;                                ///< excitation samples streamed
  std::uint32_t lost = 0;                          ///< samples lost to drive overruns (all runs)
  double stream_seconds = 0;                       ///< wall time of the excitation stream
  double samples_per_second = 0;                   ///< streamed samples per wall second
  long online_updates = 0, online_rejected = 0;
  VerificationErrors verify_batch, verify_kf, verify_rls;  ///< fresh trajectory, identified models
  std::array<double, modbus_map::kMaxJoints> drive_error_before{},
      drive_error_after{};           ///< drive's own RMS(tau - tau_ff)
  std::vector<std::string> effects;  ///< explanations of the effects diagnosed and flashed
  std::vector<std::string> effects_not_flashed;
  /// The batch fit's friction and rotor inertia are per motor (robot.json's coupled motors at their
  /// own velocity; the online KF and RLS are lib's per-joint models either way).
  bool friction_per_motor = false;
  std::vector<std::string> table_notes;  ///< how the table holds the batch model (a coupled motor's coupling term)
  /// The drive link: measured before the runs, each run's way over it, and what the runs cost it.
  struct Link {
    std::string transport;           ///< "TCP" or "RTU"
    LinkCapacity capacity;           ///< ModbusDrive::measure_link before the excitation
    std::vector<std::string> plans;  ///< each run's StreamPlan::line, in order
    long transactions = 0;           ///< ring transactions of every run (one per block)
    long bytes = 0;                  ///< their bytes on the wire, both ways
    long samples = 0;                ///< samples received in every run
  } link;
  bool flashed = false;
  TableStatus flash_status = TableStatus::ok;
  std::string flash_message;
  double total_seconds = 0;
};

/// Runs the whole loop on the drive at options.uri. Throws InputError (bad options, wrong robot,
/// lost samples, transport failure) with a message in words; DriveFaultError when the drive trips
/// (samples kept, see stream_run). If the verification run with the newly flashed table trips, the
/// table active before is flashed back first and the message says so.
CalibrateResult calibrate(const RobotDescription& robot, const CalibrateOptions& options, std::ostream& progress);

void print_calibrate_report(std::ostream& out, const CalibrateResult& r);

/// The `--report` JSON document of `dyncal calibrate` (schema in docs/cli.md).
nlohmann::json calibrate_report_json(const CalibrateResult& r);

/// Why the drive did not take a table, in words (its active table is unchanged either way): the
/// table's fault ("the drive rejected the table: a value is NaN or infinite"), or, for
/// TableStatus::store_failed, the drive's own: it took the table but could not write its flash.
std::string table_refusal(TableStatus status);

/// Outcome of flash_and_verify: flashed (and read back identical), else the drive's reason.
struct FlashOutcome {
  bool flashed = false;
  TableStatus status = TableStatus::ok;
  std::string message;
};

/// Flashes `table` (staging bank, commit, read-back comparison), then runs `verify` with it active.
/// If `verify` throws DriveFaultError (the drive tripped with the new table), the table that was
/// active before is flashed back and the error rethrown saying so. A table the drive rejects is
/// returned as not flashed (`verify` not run). Throws InputError on transport failure.
FlashOutcome flash_and_verify(linux_port::ModbusDrive& drive, const ParameterTable& table,
                              const std::function<void()>& verify);

/// One streamed run: its name in messages and fault-log names, periods, sample rate [Hz], and the
/// directory a fault leaves its samples in.
struct StreamRun {
  std::string name;
  int periods = 1;
  double sample_rate_hz = 1000;
  std::string fault_dir = ".";
  /// Start the run with the identify_payload command instead of start (the drive identifies the
  /// payload on the last link while it plays; docs/payload.md "On the drive").
  bool identify_payload = false;
  /// Start it with the trace command (the drive records the whole run; stream_plan.hpp). Not with
  /// identify_payload.
  bool trace = false;
};

/// Drive samples as a log: q [rad] and tau [Nm] of `joints` joints, t = seq / sample_rate_hz [s];
/// no velocity (the drive's backward difference is not kept: the pipeline differentiates q).
JointLog samples_to_log(const std::vector<port::DriveSample>& samples, double sample_rate_hz, int joints);

/// Streams one run of `trajectory` from the drive into a log (q and tau; t from seq), handing each
/// sample to `on_sample` (if set) as it arrives. Throws InputError on transport errors or lost
/// samples, and DriveFaultError when the drive stops on a fault: the samples recorded before it are
/// first written (write_csv_log) to run.fault_dir/dyncal-fault-NAME-YYYYmmddTHHMMSS.csv (-2, -3 ...
/// appended rather than overwrite), which the message names. Whatever ends it before the run ends
/// by itself (an exception; SIGINT or SIGTERM, caught while it runs: host::Interrupted) first sends
/// the drive's stop command (docs/modbus.md "A host that stops stops the motion").
JointLog stream_run(linux_port::ModbusDrive& drive, const linux_port::Trajectory& trajectory, const StreamRun& run,
                    std::ostream* progress, std::uint32_t* lost, double* seconds,
                    const std::function<void(const port::DriveSample&)>& on_sample);

}  // namespace dyncal::host
