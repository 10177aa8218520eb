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
#include "dyncal_host/calibration/calibrate_options.hpp"
#include "dyncal_host/calibration/calibrate_result.hpp"
#include "dyncal_host/calibration/stream_plan.hpp"
#include "dyncal_host/diagnosis/diagnose.hpp"
#include "dyncal_host/excitation/excitation.hpp"
#include "dyncal_host/identification/pipeline/identify.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_port/modbus_drive.hpp"

namespace dyncal::host {

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
