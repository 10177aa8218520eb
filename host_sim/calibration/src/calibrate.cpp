#include "dyncal_host/calibration/calibrate.hpp"

#include <Eigen/SVD>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <memory>
#include <ostream>
#include <random>

#include "dyncal_host/calibration/online_estimators.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/interrupt.hpp"
#include "dyncal_host/common/model_terms.hpp"
#include "dyncal_host/common/number_text.hpp"
#include "dyncal_host/common/output_file.hpp"
#include "dyncal_host/common/progress.hpp"
#include "dyncal_host/excitation/excitation.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_host/identification/reports/identify_report.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/model/drive_table.hpp"

namespace dyncal::host {
namespace {

using SteadyClock = std::chrono::steady_clock;
namespace mm = dyncal::modbus_map;

double seconds_since(SteadyClock::time_point t0) {
  return std::chrono::duration<double>(SteadyClock::now() - t0).count();
}

/// Verification run: stream a fresh trajectory and read the drive's model error.
JointLog verification_run(linux_port::ModbusDrive& drive, const linux_port::Trajectory& t, const CalibrateOptions& o,
                          bool trace, std::ostream* progress, std::uint32_t* lost,
                          std::array<double, modbus_map::kMaxJoints>& drive_error) {
  StreamRun run{"verification", o.verify_periods, o.sample_rate_hz, o.fault_dir};
  run.trace = trace;
  JointLog log = stream_run(drive, t, run, progress, lost, nullptr, nullptr);
  linux_port::DriveInfo info;
  if (drive.read_info(info) != port::PortStatus::ok) throw InputError("drive: " + drive.error());
  drive_error = info.model_error_rms;
  return log;
}

constexpr const char* kFlashedMessage = "flashed, read back and compared: identical";

/// `dir`/dyncal-fault-`run`-YYYYmmddTHHMMSS.csv (local time), with -2, -3 ... before the extension
/// if that file exists: an earlier fault log is never overwritten.
std::string fault_log_path(const StreamRun& run) {
  const std::time_t now = std::time(nullptr);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%S", std::localtime(&now));
  const std::string stem = (std::filesystem::path(run.fault_dir) / ("dyncal-fault-" + run.name + "-" + stamp)).string();
  std::string path = stem + ".csv";
  for (int k = 2; std::filesystem::exists(path); ++k) path = stem + "-" + std::to_string(k) + ".csv";
  return path;
}

}  // namespace

JointLog samples_to_log(const std::vector<port::DriveSample>& samples, double sample_rate_hz, int joints) {
  const Eigen::Index S = static_cast<Eigen::Index>(samples.size());
  JointLog log;
  log.t.resize(S);
  log.q.resize(S, joints);
  log.tau.resize(S, joints);
  for (Eigen::Index s = 0; s < S; ++s) {
    const auto& d = samples[static_cast<size_t>(s)];
    log.t[s] = static_cast<double>(d.seq) / sample_rate_hz;
    for (int j = 0; j < joints; ++j) {
      log.q(s, j) = d.q[j];
      log.tau(s, j) = d.tau[j];
    }
  }
  log.source = "drive";
  return log;
}

/// Stops the run the host started unless it ends by itself (disarm): an exception or a signal that
/// ends stream_run early leaves the drive stopped, not playing until its watchdog trips.
class StopOnExit {
 public:
  explicit StopOnExit(linux_port::ModbusDrive& drive) : drive_(drive) {}
  ~StopOnExit() {
    if (armed_) stop_now();
  }
  StopOnExit(const StopOnExit&) = delete;
  StopOnExit& operator=(const StopOnExit&) = delete;
  void disarm() { armed_ = false; }
  /// Sends stop (twice more after a transport error) and disarms; says how it went.
  std::string stop_now() {
    armed_ = false;
    for (int attempt = 0; attempt < 3; ++attempt) {
      if (drive_.stop() == port::PortStatus::ok) return "the drive was stopped";
    }
    return "the stop command did not reach the drive (" + drive_.error() +
           "); its communication watchdog stops the run";
  }

 private:
  linux_port::ModbusDrive& drive_;
  bool armed_ = true;
};

namespace {

/// The error of a run that delivered nothing new for `stall_seconds`: which side stopped, from the
/// drive's own counter (samples it produced past the last one received are in its ring: the link
/// does not deliver them; none: the drive stopped).
InputError stall_error(linux_port::ModbusDrive& drive, const std::vector<port::DriveSample>& samples, long expected,
                       const std::string& run_name, double stall_seconds) {
  linux_port::DriveInfo now;
  if (drive.read_info(now) != port::PortStatus::ok) throw InputError("drive: " + drive.error());
  const std::uint32_t next = samples.empty() ? 0 : samples.back().seq + 1;
  const std::string after = " s after " + std::to_string(samples.size()) + " of " + std::to_string(expected) +
                            " samples (" + run_name + " run): ";
  if (now.produced > next)
    return InputError("drive: no new sample for " + std::to_string(static_cast<int>(stall_seconds)) + after +
                      "the drive has produced " + std::to_string(now.produced - next) +
                      " more, but the link does not deliver them");
  return InputError("drive: no new sample for " + std::to_string(static_cast<int>(stall_seconds)) + after +
                    "the drive has stalled (its produced counter stays at " + std::to_string(now.produced) + ")");
}

/// The error of a run the drive stopped with a fault; the samples recorded before it written to the
/// run's fault log (its path, or why they are lost, in the message).
DriveFaultError fault_error(linux_port::ModbusDrive& drive, const std::vector<port::DriveSample>& samples,
                            const StreamRun& run, int joints) {
  if (samples.empty()) return DriveFaultError(drive.error() + "; no sample was recorded before it");
  const std::string path = fault_log_path(run);
  const std::string count = std::to_string(samples.size()) + " samples recorded before it (" + run.name + " run)";
  try {
    write_csv_log(path, samples_to_log(samples, run.sample_rate_hz, joints));
  } catch (const InputError& e) {
    return DriveFaultError(drive.error() + "; the " + count + " are lost: " + e.what());
  }
  return DriveFaultError(drive.error() + "; the " + count + " are in " + path);
}

}  // namespace

JointLog stream_run(linux_port::ModbusDrive& drive, const linux_port::Trajectory& trajectory, const StreamRun& run,
                    std::ostream* progress, std::uint32_t* lost, double* seconds,
                    const std::function<void(const port::DriveSample&)>& on_sample) {
  linux_port::DriveInfo info;
  if (drive.read_info(info) != port::PortStatus::ok) throw InputError("drive: " + drive.error());
  const int joints = info.num_joints;
  if (info.state == mm::DriveState::fault) {  // a new run is the user's explicit reset of an earlier fault
    if (progress) *progress << "the drive stands in fault (" << linux_port::describe_fault(info) << "): reset\n";
    if (drive.reset() != port::PortStatus::ok) throw InputError("drive: " + drive.error());
  }
  if (drive.write_trajectory(trajectory, run.periods, run.sample_rate_hz) != port::PortStatus::ok)
    throw InputError("drive: " + drive.error());
  const auto t0 = SteadyClock::now();
  const InterruptScope interrupts;  // SIGINT, SIGTERM from here on: stop the run, then exit
  const port::PortStatus started = run.identify_payload ? drive.identify_payload()
                                   : run.trace          ? drive.trace()
                                                        : drive.start();
  if (started == port::PortStatus::rejected && run.trace)
    throw InputError("drive: the drive refused to trace the " + run.name + " run (" + drive.error() +
                     "): its ring cannot hold every sample the run records (its scenario's rests included); "
                     "use fewer --periods or --stream live");
  if (started != port::PortStatus::ok) throw InputError("drive: " + drive.error());
  StopOnExit stop_on_exit(drive);
  const long expected = std::lround(run.periods * trajectory.period() * run.sample_rate_hz);
  std::vector<port::DriveSample> samples;
  samples.reserve(static_cast<size_t>(expected));
  port::DriveSample block[mm::kMaxSamplesPerBlock];
  // The run's samples as progress (progress.hpp: a terminal line when the program set one).
  std::unique_ptr<Progress> bar;
  if (progress)
    bar = std::make_unique<Progress>(run.name + (run.trace ? " run, uploading" : " run, streaming"),
                                     static_cast<double>(expected), "samples");
  // Every wait has a deadline: a drive that delivers nothing new for kStallSeconds while it should
  // be playing has stalled (a healthy one delivers a sample every period, at least 100 Hz).
  constexpr double kStallSeconds = 10.0;
  auto last_progress = SteadyClock::now();
  for (;;) {
    if (const int signal = interrupt_signal()) {
      const std::string stopped = stop_on_exit.stop_now();
      throw Interrupted(signal, "interrupted by " + signal_name(signal) + " during the " + run.name + " run after " +
                                    std::to_string(samples.size()) + " samples: " + stopped);
    }
    int n = 0;
    const port::PortStatus st = drive.read(block, mm::kMaxSamplesPerBlock, &n);
    if (st == port::PortStatus::end_of_stream) {
      stop_on_exit.disarm();  // the run ended by itself
      break;
    }
    if (n > 0) {
      last_progress = SteadyClock::now();
    } else if (std::chrono::duration<double>(SteadyClock::now() - last_progress).count() > kStallSeconds) {
      throw stall_error(drive, samples, expected, run.name, kStallSeconds);
    }
    if (st == port::PortStatus::transport_error) throw InputError("drive: " + drive.error());
    if (st == port::PortStatus::device_fault) {
      stop_on_exit.disarm();  // the drive stopped the run itself; its fault stands until a reset
      bar.reset();            // the progress line erased before the fault is told
      throw fault_error(drive, samples, run, joints);
    }
    if (st == port::PortStatus::sequence_gap) {
      throw InputError(
          "drive overrun: " + std::to_string(drive.lost()) +
          " samples lost (the drive's overrun counter; the host read too slowly: use --stream trace, a lower --rate, "
          "or --lockstep on the simulated drive)");
    }
    samples.insert(samples.end(), block, block + n);
    if (on_sample) {
      for (int k = 0; k < n; ++k) on_sample(block[k]);
    }
    if (bar) bar->update(static_cast<double>(samples.size()));
  }
  bar.reset();
  if (seconds) *seconds = seconds_since(t0);
  if (lost) *lost += drive.lost();
  for (int j = 0; j < joints; ++j) {  // a saturated torque is a bound, not a measurement
    const long n = drive.saturated()[static_cast<size_t>(j)];
    if (n > 0)
      throw InputError("drive: joint " + std::to_string(j + 1) + "'s torque read the stream's full scale in " +
                       std::to_string(n) + " of " + std::to_string(samples.size()) + " samples (" + run.name +
                       " run): saturated, not measured; the run demands more torque than the drive measures");
  }
  if (samples.size() < 10) throw InputError("drive delivered only " + std::to_string(samples.size()) + " samples");
  return samples_to_log(samples, run.sample_rate_hz, joints);
}

std::string table_refusal(TableStatus status) {
  if (status == TableStatus::store_failed)  // the table passed; the drive's flash did not take it
    return "the drive took the table but could not write it to its flash store (a storage fault on the drive; its "
           "log says why)";
  return std::string("the drive rejected the table: ") + to_string(status);
}

FlashOutcome flash_and_verify(linux_port::ModbusDrive& drive, const ParameterTable& table,
                              const std::function<void()>& verify) {
  ParameterTable previous;
  TableStatus previous_status = TableStatus::ok;
  if (drive.read(previous, &previous_status) != port::PortStatus::ok) {
    throw InputError("drive: cannot read the active table before flashing: " +
                     (previous_status != TableStatus::ok ? to_string(previous_status) : drive.error()));
  }
  FlashOutcome f;
  const port::PortStatus st = drive.write(table, &f.status);
  if (st == port::PortStatus::transport_error) throw InputError("flash failed: " + drive.error());
  if (st != port::PortStatus::ok) {
    f.message = table_refusal(f.status);
    return f;
  }
  f.flashed = true;
  f.message = kFlashedMessage;
  try {
    verify();
  } catch (const DriveFaultError& fault) {
    // The new table made the drive trip: the one it replaced goes back before anything else. The
    // drive takes no table in fault: this is the explicit reset that clears it.
    TableStatus reason = TableStatus::ok;
    port::PortStatus back = drive.reset();
    if (back == port::PortStatus::ok) back = drive.write(previous, &reason);
    throw DriveFaultError("with the new table, " + std::string(fault.what()) + ". " +
                          (back == port::PortStatus::ok
                               ? "The previous table was flashed back."
                               : "Flashing the previous table back failed: " +
                                     (back == port::PortStatus::rejected ? to_string(reason) : drive.error())));
  }
  return f;
}

namespace {

// The run settings, checked before the drive is contacted against what the drive accepts
// (docs/modbus.md): a bad value is named here, not discovered as a Modbus exception after start.
void check_run_options(const CalibrateOptions& o) {
  const double f_f = o.excitation ? o.excitation->f_f : o.f_f;
  const int harmonics = o.excitation ? o.excitation->harmonics : o.harmonics;
  if (o.candidates < 1) throw InputError("--candidates " + std::to_string(o.candidates) + " must be >= 1");
  for (const auto& [name, periods] :
       {std::pair{"--periods", o.periods}, std::pair{"--verify-periods", o.verify_periods}}) {
    const std::string given = std::string(name) + " " + std::to_string(periods);
    switch (mm::refused_trajectory_setting(o.sample_rate_hz, f_f, harmonics, periods)) {
      case mm::TrajectorySetting::none:
        break;
      case mm::TrajectorySetting::sample_rate:
        throw InputError("--rate " + number_text(o.sample_rate_hz) + " Hz must lie in " +
                         number_text(mm::kMinSampleRateHz) + ".." + number_text(mm::kMaxSampleRateHz) + " Hz");
      case mm::TrajectorySetting::omega_f:
        throw InputError("--omega-f " + number_text(f_f) + " Hz must lie in (0, " + number_text(mm::kMaxFundamentalHz) +
                         "] Hz");
      case mm::TrajectorySetting::harmonics:
        throw InputError("--harmonics " + std::to_string(harmonics) + " must lie in 1.." +
                         std::to_string(mm::kMaxHarmonics));
      case mm::TrajectorySetting::periods:
        throw InputError(given + " must lie in 1.." + std::to_string(mm::kMaxPeriods));
      case mm::TrajectorySetting::run_length:
        throw InputError(
            given + " at --omega-f " + number_text(f_f) + " Hz and --rate " + number_text(o.sample_rate_hz) +
            " Hz make a run of " + number_text(mm::run_samples(periods, f_f, o.sample_rate_hz)) +
            " samples, longer than a drive plays (" + number_text(mm::kMaxRunSamples) + ", docs/modbus.md)");
    }
  }
}

/// The law file of the excitation run (docs/cli.md "Law file") at `path`, with the table active
/// during it as `path` with the extension .table (its bytes as the drive held them).
void write_law_file(const std::string& path, const RobotDescription& robot, const linux_port::Trajectory& excitation,
                    const CalibrateOptions& o, const linux_port::DriveControlLaw& law,
                    const std::vector<std::uint8_t>& table) {
  const std::filesystem::path table_path = std::filesystem::path(path).replace_extension(".table");
  nlohmann::json j;
  j["comment"] =
      "the control law of dyncal calibrate's excitation run (calibrate --save-law): identify --method iv "
      "--law this file, with the log of --save-log";
  j["trajectory"] = trajectory_to_json(robot, excitation);
  j["periods"] = o.periods;
  j["sample_rate_hz"] = o.sample_rate_hz;
  j["control_rate_hz"] = law.control_rate_hz;
  j["kp"] = nlohmann::json::array();
  j["kd"] = nlohmann::json::array();
  for (int k = 0; k < robot.num_joints; ++k) {
    if (!(law.kp[k] > 0.0) || !(law.kd[k] > 0.0))
      throw InputError("drive: the PD gains of joint " + std::to_string(k + 1) + " read back as not > 0");
    j["kp"].push_back(law.kp[k]);
    j["kd"].push_back(law.kd[k]);
  }
  j["feed_forward_table"] = table_path.filename().string();
  write_output_file(table_path.string(), std::string_view(reinterpret_cast<const char*>(table.data()), table.size()),
                    "feed-forward table");
  write_output_file(path, j.dump(2) + "\n", "drive law");
}

}  // namespace

namespace {

/// Refuses (InputError) a fault directory that is not one, or a --save-log / --save-law path in no
/// directory, before any motion.
void check_output_folders(const CalibrateOptions& o) {
  if (!std::filesystem::is_directory(o.fault_dir))
    throw InputError("fault directory '" + o.fault_dir + "' is not a directory");
  for (const auto& [what, path] : {std::pair{"log", o.save_log}, std::pair{"law", o.save_law}}) {
    if (path.empty()) continue;
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    if (!parent.empty() && !std::filesystem::is_directory(parent))
      throw InputError(std::string("cannot write the ") + what + " '" + path + "': no directory '" + parent.string() +
                       "'");
  }
}

/// The drive at `uri`, checked to be the robot's (joint count, robot id). Throws InputError.
std::unique_ptr<linux_port::ModbusDrive> connected_drive(const std::string& uri, const RobotDescription& robot,
                                                         const CompiledRobot& compiled) {
  std::string error;
  auto drive = linux_port::ModbusDrive::connect(uri, &error);
  if (!drive) throw InputError(error);
  linux_port::DriveInfo info;
  if (drive->read_info(info) != port::PortStatus::ok) throw InputError("drive: " + drive->error());
  if (info.num_joints != compiled.num_joints)
    throw InputError("the drive has " + std::to_string(info.num_joints) + " joints, robot '" + robot.name + "' " +
                     std::to_string(compiled.num_joints));
  if (info.robot_id != compiled.robot_id)
    throw InputError("the drive's robot id does not match robot '" + robot.name + "'");

  return drive;
}

/// r.link's capacity: the transaction time with the samples a block carries, and the drive's ring.
void measure_link(linux_port::ModbusDrive& drive, CalibrateResult& r) {
  constexpr int kProbeTransactions = 8;
  if (drive.measure_link(kProbeTransactions, &r.link.capacity.transaction_seconds) != port::PortStatus::ok)
    throw InputError("drive: " + drive.error());
  r.link.transport = drive.transport();
  r.link.capacity.samples_per_second = drive.samples_per_block() / std::max(1e-9, r.link.capacity.transaction_seconds);
  r.link.capacity.ring_capacity = drive.ring_capacity();
}

/// The excitation: --excitation's, else the best of o.candidates random ones; its cond(K) into r.
linux_port::Trajectory chosen_excitation(const RobotDescription& robot, const CalibrateOptions& o, CalibrateResult& r,
                                         std::ostream& progress) {
  linux_port::Trajectory excitation;
  if (o.excitation) {
    excitation = *o.excitation;
    excitation_quality(robot, excitation, FrictionModel::eq7, 400, &r.trajectory_cond, nullptr);
  } else {
    excitation = default_excitation(robot, o.f_f, o.harmonics, o.candidates, o.seed, &r.trajectory_cond);
  }
  progress << "excitation: Fourier series (Eq. 27), L = " << excitation.harmonics << ", f_f = " << excitation.f_f
           << " Hz" << (o.excitation ? " (designed)" : "") << ", " << o.periods << " periods at " << o.sample_rate_hz
           << " Hz, cond(K) = " << std::setprecision(3) << r.trajectory_cond << "\n";
  return excitation;
}

/// The bytes of the drive's active table. Throws InputError.
std::vector<std::uint8_t> active_table(linux_port::ModbusDrive& drive) {
  std::vector<std::uint8_t> bytes(kTableMaxBytes);
  int size = 0;
  if (drive.read_active_bytes(bytes.data(), kTableMaxBytes, &size) != port::PortStatus::ok)
    throw InputError("drive: " + drive.error());
  bytes.resize(static_cast<size_t>(size));
  return bytes;
}

/// `batch_set` with the effects `dyncal diagnose` finds on the excitation `log` and the declared
/// parameters re-estimated with them (r.effects, r.effects_not_flashed).
ParameterSet with_diagnosed_effects(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& io,
                                    const ParameterSet& batch_set, CalibrateResult& r, std::ostream& progress) {
  DiagnoseOptions dopt;
  dopt.identify = io;
  dopt.identify.sign_constraints = false;  // the diagnosis's statistics are unconstrained fits
  const DiagnoseResult d = diagnose(robot, log, dopt);
  ParameterSet out = diagnosed_parameter_set(batch_set, d, &r.effects_not_flashed);
  for (const auto& e : d.effects) r.effects.push_back(e.explanation);
  progress << "diagnosis: " << d.effects.size() << " effect(s) found";
  for (const auto& e : d.effects) progress << "\n  " << e.explanation;
  progress << "\n";
  return out;
}

}  // namespace

CalibrateResult calibrate(const RobotDescription& robot, const CalibrateOptions& o, std::ostream& progress) {
  const auto t0 = SteadyClock::now();
  check_run_options(o);
  const CompiledRobot& compiled = compiled_robot_for(robot);
  const int term_set = built_term_set_index(o.terms);
  const TermSetModel& model = compiled.models[static_cast<size_t>(term_set)];
  check_output_folders(o);
  const std::unique_ptr<linux_port::ModbusDrive> drive = connected_drive(o.uri, robot, compiled);

  CalibrateResult r;
  r.num_joints = robot.num_joints;
  std::ostream* prog = o.progress ? &progress : nullptr;
  // The link, as the stream uses it: its transaction time with the samples a block carries, and
  // the drive's ring; each run then streams live or is traced (stream_plan.hpp).
  measure_link(*drive, r);
  const linux_port::ModbusDrive::LinkStats link_before = drive->link_stats();
  auto plan = [&](const char* name, const linux_port::Trajectory& t, int periods) {
    const long samples = std::lround(periods * t.period() * o.sample_rate_hz);
    const StreamPlan p = plan_stream(o.stream, r.link.capacity, name, samples, o.sample_rate_hz, periods);
    progress << p.line << "\n";
    r.link.plans.push_back(p.line);
    return p.trace;
  };
  // 1. Excitation: stream, then online estimators sample by sample and the batch fit.
  const linux_port::Trajectory excitation = chosen_excitation(robot, o, r, progress);
  SampleSink sink;
  start_online_estimators(model, robot.qd_max, o, sink);
  // The table active during the excitation (--save-law).
  const std::vector<std::uint8_t> feed_forward =
      o.save_law.empty() ? std::vector<std::uint8_t>() : active_table(*drive);
  StreamRun excitation_run{"excitation", o.periods, o.sample_rate_hz, o.fault_dir};
  excitation_run.trace = plan("excitation", excitation, o.periods);
  const JointLog log = stream_run(*drive, excitation, excitation_run, prog, &r.lost, &r.stream_seconds, sink.push);
  if (!o.save_log.empty()) {
    write_csv_log(o.save_log, log);
    progress << "excitation log written to " << o.save_log << "\n";
  }
  if (!o.save_law.empty()) {
    linux_port::DriveControlLaw law;  // the gains the drive set when the excitation started
    if (drive->read_control_law(law) != port::PortStatus::ok) throw InputError("drive: " + drive->error());
    write_law_file(o.save_law, robot, excitation, o, law, feed_forward);
    progress << "control law of the excitation run written to " << o.save_law << "\n";
  }
  sink.finish(r);
  r.samples = static_cast<long>(log.samples());
  r.samples_per_second = static_cast<double>(r.samples) / std::max(1e-9, r.stream_seconds);
  IdentifyOptions io = o.identify;
  io.terms = o.terms;
  // Friction and rotor inertia belong to motors: a motor that robot.json couples to two joints
  // (the TX40's motor 6 on q5 + q6) is fitted at its own velocity, unless
  // options.identify.friction_per_joint. The drive's table carries its terms as a coupling term
  // (parameter_table), which the feed-forward applies at the motor's velocity.
  r.batch = identify(robot, log, io);
  for (const auto& p : r.batch.params) {
    r.names.push_back(p.name);
    r.phi_batch.push_back(p.value);
  }
  r.friction_per_motor = r.batch.friction_per_motor;
  ParameterSet batch_set = parameter_set(r.batch);
  if (o.keep_trace) r.trace = predicted_trace(robot, log, io, batch_set);
  // 2. Fresh trajectory with the drive's current table, flash, same trajectory again.
  const auto fresh = default_excitation(robot, o.f_f, o.harmonics, 1, o.seed + 1000, nullptr);
  const bool trace_verification = plan("verification", fresh, o.verify_periods);
  progress << "verification run with the drive's current table\n";
  const JointLog vlog = verification_run(*drive, fresh, o, trace_verification, prog, &r.lost, r.drive_error_before);
  const auto verify = [&model](const JointLog& run, const std::vector<double>& phi,
                               const std::vector<EffectTerm>& effects,
                               double cutoff) { return verify_parameters(model, run, phi, effects, cutoff); };
  {
    // The batch estimate as the drive would apply it: the table's parameters and effect terms.
    const DriveTableContent batch_table = drive_table_content(batch_set, robot);
    r.verify_batch = verify(vlog, batch_table.values, batch_table.effects, o.online_cutoff_hz);
  }
  r.verify_kf = verify(vlog, r.phi_kf, {}, o.online_cutoff_hz);
  r.verify_rls = verify(vlog, r.phi_rls, {}, o.online_cutoff_hz);
  if (o.flash) {
    if (o.diagnose) {
      // The same analysis as `dyncal diagnose` on the excitation; the table then carries the effects
      // found and the declared parameters re-estimated with them.
      batch_set = with_diagnosed_effects(robot, log, io, batch_set, r, progress);
    }
    const ParameterTable table = parameter_table(batch_set, robot, &r.table_notes);
    const FlashOutcome f = flash_and_verify(*drive, table, [&] {
      progress << kFlashedMessage << "\nverification run with the new table\n";
      verification_run(*drive, fresh, o, trace_verification, prog, &r.lost, r.drive_error_after);
    });
    r.flashed = f.flashed;
    r.flash_status = f.status;
    r.flash_message = f.message;
    if (!f.flashed) progress << r.flash_message << "\n";
  }
  r.link.transactions = drive->link_stats().transactions - link_before.transactions;
  r.link.bytes = drive->link_stats().bytes - link_before.bytes;
  r.link.samples = drive->link_stats().samples - link_before.samples;
  r.total_seconds = seconds_since(t0);
  return r;
}

void print_calibrate_report(std::ostream& out, const CalibrateResult& r) {
  out << std::fixed;
  out << "\ncalibration: " << r.samples << " samples streamed in " << std::setprecision(1) << r.stream_seconds << " s ("
      << std::setprecision(0) << r.samples_per_second << " samples/s), " << r.lost << " lost; online updates "
      << r.online_updates << " (" << r.online_rejected << " rejected)\n";
  const auto& l = r.link;
  if (l.transactions > 0 && l.samples > 0) {
    out << "link: " << l.transport << ", " << l.transactions << " ring transactions for " << l.samples
        << " samples in all runs (" << std::setprecision(1)
        << static_cast<double>(l.samples) / static_cast<double>(l.transactions) << " per transaction, "
        << static_cast<double>(l.bytes) / static_cast<double>(l.samples)
        << " bytes per sample on the wire); measured before the runs: " << std::setprecision(0)
        << l.capacity.samples_per_second << " samples/s live (" << std::setprecision(2)
        << 1e3 * l.capacity.transaction_seconds << " ms per transaction), ring of " << l.capacity.ring_capacity
        << " samples\n";
    for (const auto& p : l.plans) out << "  " << p << "\n";
  }
  if (!r.batch.prismatic_joints.empty()) {
    out << "prismatic joint" << (r.batch.prismatic_joints.size() > 1 ? "s" : "");
    for (const int j : r.batch.prismatic_joints) out << " " << j;
    out << ": the torques below [Nm] are forces [N] there\n";
  }
  out << "batch fit (" << r.batch.method << ", " << r.batch.model
      << (r.friction_per_motor ? ", friction and rotor inertia per motor" : "")
      << "), cross-validated on the excitation run:\n";
  out << "  joint    RMS [Nm]   rel. RMS      R2 e_T_abs\n";
  for (const auto& j : r.batch.joints) {
    out << "  " << std::setw(5) << j.joint << std::setprecision(3) << std::setw(11) << j.rms << std::setw(11)
        << j.relative_rms << std::setprecision(4) << std::setw(8) << j.r2 << std::setw(8) << j.e_T_abs << "\n";
  }
  out << "fresh trajectory, prediction RMS [Nm] of each estimate (online path, causal filter):\n";
  out << "  joint     RMS tau       batch          KF         RLS\n";
  for (int j = 0; j < r.num_joints; ++j) {
    out << "  " << std::setw(5) << j + 1 << std::setprecision(3) << std::setw(12) << r.verify_batch.rms_tau[j]
        << std::setw(12) << r.verify_batch.rms[j] << std::setw(12) << r.verify_kf.rms[j] << std::setw(12)
        << r.verify_rls.rms[j] << "\n";
  }
  if (!r.effects.empty()) {
    out << "effects diagnosed and flashed with the table:\n";
    for (const auto& e : r.effects) out << "  " << e << "\n";
    for (const auto& e : r.effects_not_flashed) out << "  (not flashed: " << e << " - no table term holds it)\n";
  }
  for (const auto& n : r.table_notes) out << "table: " << n << "\n";
  out << "flash: " << r.flash_message << "\n";
  if (r.flashed) {
    out << "drive model error RMS(tau - tau_ff) [Nm] on the fresh trajectory, before -> after the flash:\n";
    out << "  joint      before       after   reduction\n";
    for (int j = 0; j < r.num_joints; ++j) {
      const double b = r.drive_error_before[j], a = r.drive_error_after[j];
      out << "  " << std::setw(5) << j + 1 << std::setprecision(3) << std::setw(12) << b << std::setw(12) << a
          << std::setprecision(1) << std::setw(11) << (b > 0 ? 100.0 * (1.0 - a / b) : 0.0) << "%\n";
    }
  }
  out << "total wall time " << std::setprecision(1) << r.total_seconds << " s\n";
  out << std::defaultfloat;
}

nlohmann::json calibrate_report_json(const CalibrateResult& r) {
  nlohmann::json j;
  j["batch"] = identify_report_json(r.batch);
  j["samples"] = r.samples;
  j["lost"] = r.lost;
  j["samples_per_second"] = r.samples_per_second;
  j["link"] = {{"transport", r.link.transport},
               {"samples_per_second_live", r.link.capacity.samples_per_second},
               {"transaction_seconds", r.link.capacity.transaction_seconds},
               {"ring_capacity", r.link.capacity.ring_capacity},
               {"runs", r.link.plans},
               {"transactions", r.link.transactions},
               {"bytes", r.link.bytes},
               {"samples", r.link.samples}};
  j["trajectory_cond"] = r.trajectory_cond;
  j["params"] = nlohmann::json::array();
  for (size_t i = 0; i < r.names.size(); ++i) {
    j["params"].push_back(
        {{"name", r.names[i]}, {"batch", r.phi_batch[i]}, {"kf", r.phi_kf[i]}, {"rls", r.phi_rls[i]}});
  }
  j["joints"] = nlohmann::json::array();
  for (size_t k = 0; k < static_cast<size_t>(r.num_joints); ++k) {
    j["joints"].push_back({{"joint", k + 1},
                           {"verify_rms_batch", r.verify_batch.rms[k]},
                           {"verify_rms_kf", r.verify_kf.rms[k]},
                           {"verify_rms_rls", r.verify_rls.rms[k]},
                           {"drive_error_before", r.drive_error_before[k]},
                           {"drive_error_after", r.drive_error_after[k]}});
  }
  j["friction_per"] = r.friction_per_motor ? "motor" : "joint";
  j["table_notes"] = r.table_notes;
  j["flashed"] = r.flashed;
  j["flash_message"] = r.flash_message;
  j["total_seconds"] = r.total_seconds;
  return j;
}

}  // namespace dyncal::host
