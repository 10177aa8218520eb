// dyncal monitor: contacts in a log found by the generalised-momentum observer of the calibrated
// model, with thresholds from the calibration's own residual statistics (docs/monitor.md).
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/monitoring/contact_monitor.hpp"
#include "dyncal_host/report/torque_series.hpp"
#include "dyncal_port/modbus_drive.hpp"
#include "report_outputs.hpp"

namespace dyncal::app {
namespace {

struct MonitorSettings {
  LogOption log;
  std::string params, reference, plots, drive;
  ReportOutputs out;
  double alarms_per_hour = 0.01;
  double gain = 0;
};

/// Prints the thresholds with their basis; returns them as the report's JSON list.
nlohmann::json print_thresholds(const MonitorSettings& s, const host::ResidualStatistics& stats,
                                const std::vector<host::ContactThreshold>& thresholds) {
  std::cout << "thresholds for " << s.alarms_per_hour << " false alarms per hour (residual statistics of "
            << (stats.source.empty() ? s.params : stats.source) << ", " << stats.samples
            << " samples; docs/monitor.md):\n"
            << "  joint   mean [Nm]    std [Nm]  threshold |r - mean| [Nm]\n";
  nlohmann::json threshold_list = nlohmann::json::array();
  for (size_t j = 0; j < thresholds.size(); ++j) {
    const host::ContactThreshold& c = thresholds[j];
    std::cout << std::setw(7) << j + 1 << std::setw(12) << std::setprecision(4) << stats.mean[j] << std::setw(12)
              << stats.std[j] << std::setw(14) << c.value;
    if (c.peak_bound)
      std::cout << "  the calibration's own peak: its residual's tails are heavier than Gaussian (Gaussian "
                << c.gaussian << "); the rate is not established on this joint";
    std::cout << "\n";
    threshold_list.push_back({{"joint", j + 1},
                              {"value", c.value},
                              {"gaussian", c.gaussian},
                              {"basis", c.peak_bound ? "calibration peak" : "gaussian"}});
  }
  std::cout << "note: the rate holds for motion like the calibration's; where the acceleration jumps (a stop or a "
               "start without a jerk limit) the residual crosses more often (docs/monitor.md, \"Open\")\n";
  return threshold_list;
}

/// --drive: the thresholds into the drive's collision monitor (docs/modbus.md "Collision monitor"),
/// checked against the drive first: its robot and joints, and its control rate, which must be the
/// statistics' sample rate (the drive runs the observer at its control rate).
int write_drive_monitor(const MonitorSettings& s, const host::RobotDescription& robot,
                        const host::ResidualStatistics& stats) {
  const host::CompiledRobot& compiled = host::compiled_robot_for(robot);
  std::string error;
  auto drive = linux_port::ModbusDrive::connect(s.drive, &error);
  if (!drive) throw host::InputError(error);
  linux_port::DriveInfo info;
  if (drive->read_info(info) != port::PortStatus::ok) throw host::InputError("drive: " + drive->error());
  if (info.robot_id != compiled.robot_id || info.num_joints != robot.num_joints)
    throw host::InputError("the drive's robot is not '" + robot.name + "' of the parameter file");
  linux_port::DriveControlLaw law;
  if (drive->read_control_law(law) != port::PortStatus::ok) throw host::InputError("drive: " + drive->error());
  if (!(std::abs(law.control_rate_hz * stats.period - 1.0) <= 0.01)) {
    std::ostringstream m;
    m << "the drive's control rate is " << law.control_rate_hz << " Hz, the residual statistics were taken at "
      << 1.0 / stats.period << " Hz: thresholds hold only at the rate they were measured at (calibrate at the control "
      << "rate)";
    throw host::InputError(m.str());
  }
  const std::vector<host::ContactThreshold> thresholds = host::contact_thresholds(stats, s.alarms_per_hour);
  std::cout << "monitor: generalised-momentum observer, K = " << stats.gain << " 1/s (time constant "
            << std::setprecision(3) << 1e3 / stats.gain << " ms), on the drive at " << std::setprecision(6)
            << law.control_rate_hz << " Hz\n";
  const nlohmann::json threshold_list = print_thresholds(s, stats, thresholds);
  linux_port::DriveMonitor m;
  m.gain = stats.gain;
  for (size_t j = 0; j < thresholds.size(); ++j) {
    m.threshold[j] = thresholds[j].value;
    m.mean[j] = stats.mean[j];
    m.band[j] = stats.band[j];
  }
  if (drive->write_monitor(m) != port::PortStatus::ok)
    throw host::InputError("drive: the collision monitor was not written: " + drive->error());
  std::cout << "written to the drive's collision monitor: it watches the runs started from now on (a collision "
               "stops the trajectory with fault 5, docs/modbus.md)\n";
  if (!s.out.wanted()) return 0;
  return finish_report(s.out,
                       {{"robot", robot.name},
                        {"drive", s.drive},
                        {"params", s.params},
                        {"alarms_per_hour", s.alarms_per_hour},
                        {"statistics", host::residual_statistics_json(stats)},
                        {"thresholds", threshold_list}},
                       {s.params});
}

/// The residual statistics the thresholds come from: --reference's contact-free log observed with
/// --gain, else the parameter file's ("monitor"). Throws InputError.
host::ResidualStatistics monitor_statistics(const MonitorSettings& s, const host::RobotDescription& robot,
                                            const host::ParameterSet& params) {
  host::ResidualStatistics stats;
  if (!s.reference.empty()) {
    const host::ObserverRun ref = host::run_observer(robot, s.log.load_logs(robot, {s.reference}), params, s.gain);
    stats = host::residual_statistics(ref, s.reference);
  } else {
    if (s.gain > 0)
      throw host::InputError(
          "--gain sets the observer of --reference: the parameter file's statistics "
          "were taken with their own gain");
    const nlohmann::json file = read_json_file(s.params);
    if (!file.contains("monitor") || file["monitor"].is_null())
      throw host::InputError(s.params +
                             " has no residual statistics (\"monitor\", written by dyncal identify --params): give "
                             "--reference LOG, a log of contact-free motion");
    stats = host::read_residual_statistics(file["monitor"], s.params);
  }
  return stats;
}

/// Refuses (InputError) a log whose rate or gain is further from the statistics' than `tolerance`
/// allows (their false-alarm rate at most doubles, docs/monitor.md "Another rate"); notes a change
/// within it.
void check_log_rate(host::ObserverRun& run, const host::ResidualStatistics& stats, double tolerance) {
  const double period_change = std::abs(run.period / stats.period - 1.0);
  const double gain_change = std::abs(run.gain / stats.gain - 1.0);
  if (std::max(period_change, gain_change) > tolerance)
    throw host::InputError("the log is sampled every " + std::to_string(run.period * 1e3) +
                           " ms, the residual statistics every " + std::to_string(stats.period * 1e3) + " ms (" +
                           std::to_string(100 * std::max(period_change, gain_change)) + " % apart): beyond the " +
                           std::to_string(100 * tolerance) +
                           " % within which their false-alarm rate at most doubles; give --reference LOG, a "
                           "contact-free log at this rate");
  if (period_change > 0 || gain_change > 0) {
    std::ostringstream note;
    note << std::setprecision(3) << "rate: the log is sampled every " << run.period * 1e3
         << " ms, the residual statistics every " << stats.period * 1e3 << " ms (" << 100 * period_change << " % apart"
         << (gain_change > 0 ? ", gain lowered to 1 / dt, " : ", gain as taken, ") << 100 * gain_change
         << " % change): within the " << 100 * tolerance
         << " % where the false-alarm rate at most doubles (docs/monitor.md \"Another rate\")";
    run.notes.push_back(note.str());
  }
}

int run_monitor(MonitorSettings& s) {
  prepare_report_outputs(s.out);
  const host::ParameterSet params = host::read_parameter_file(s.params);
  if (s.log.robot.name.empty()) s.log.robot.name = params.robot;
  if (s.log.robot.name != params.robot)
    throw host::InputError(s.params + ": parameters are for robot '" + params.robot + "', not '" + s.log.robot.name +
                           "'");
  const auto robot = s.log.load_robot();
  const host::ResidualStatistics stats = monitor_statistics(s, robot, params);
  if (static_cast<int>(stats.std.size()) != robot.num_joints)
    throw host::InputError(s.params + ": the residual statistics are for " + std::to_string(stats.std.size()) +
                           " joints, the robot has " + std::to_string(robot.num_joints));
  if (!s.drive.empty()) {
    if (!s.log.data.empty() || !s.plots.empty())
      throw host::InputError(
          "--drive sets the drive's collision monitor; --data and --plots read a log: one or the other");
    return write_drive_monitor(s, robot, stats);
  }
  if (s.log.data.empty()) throw host::InputError("--data LOG is required (or --drive URI)");
  // The statistics at the log's own rate (docs/monitor.md "Another rate"): their gain, lowered to
  // 1 / dt where this log is a little slower, within the tolerance the false-alarm rate allows.
  const std::vector<host::ContactThreshold> thresholds = host::contact_thresholds(stats, s.alarms_per_hour);
  const double tolerance = host::statistics_rate_tolerance(stats, thresholds);
  host::ObserverRun run = host::run_observer(robot, s.log.load_log(robot), params, stats.gain, stats.band,
                                             host::ResidualKind::momentum_observer, 1.0);
  check_log_rate(run, stats, tolerance);
  const std::vector<host::Contact> contacts = host::detect_contacts(run, stats, thresholds);

  std::cout << "monitor: generalised-momentum observer, K = " << stats.gain << " 1/s (time constant "
            << std::setprecision(3) << 1e3 / stats.gain << " ms), " << 1.0 / run.period << " Hz\n";
  for (const auto& n : run.notes) std::cout << "note: " << n << "\n";
  const nlohmann::json threshold_list = print_thresholds(s, stats, thresholds);
  std::cout << "contacts: " << contacts.size() << "\n";
  nlohmann::json list = nlohmann::json::array();
  for (const auto& c : contacts) {
    std::cout << "  " << std::fixed << std::setprecision(3) << c.start << " s to " << c.end << " s, joints";
    for (int j : c.joints) std::cout << " " << j;
    std::cout << "; peak |r - mean| [Nm]:";
    for (double p : c.peak) std::cout << " " << std::setprecision(1) << p;
    std::cout << std::defaultfloat << "\n";
    list.push_back(
        {{"start", c.start}, {"end", c.end}, {"first_joint", c.first_joint}, {"joints", c.joints}, {"peak", c.peak}});
  }
  if (!s.plots.empty()) {
    const auto files = host::write_contact_plots(run, stats, thresholds, contacts, s.plots);
    std::cout << "plots: " << files.size() << " SVG files in " << s.plots << "\n";
  }
  if (!s.out.wanted()) return 0;
  nlohmann::json report = {{"robot", robot.name},
                           {"data", s.log.data},
                           {"params", s.params},
                           {"alarms_per_hour", s.alarms_per_hour},
                           {"statistics", host::residual_statistics_json(stats)},
                           {"thresholds", threshold_list},
                           {"notes", run.notes},
                           {"contacts", list}};
  if (s.out.page()) {  // |r - mean| against the bound it is compared with, over the log
    Eigen::MatrixXd residual(run.r.rows(), run.r.cols()), bound(run.r.rows(), run.r.cols());
    for (Eigen::Index k = 0; k < run.r.rows(); ++k)
      for (int j = 0; j < static_cast<int>(run.r.cols()); ++j) {
        residual(k, j) = std::abs(run.r(k, j) - stats.mean[static_cast<size_t>(j)]);
        bound(k, j) = host::contact_limit(run, thresholds, k, j);
      }
    report["residual_series"] = host::residual_envelope_json(run.t, residual, bound);
  }
  std::vector<std::string> inputs = s.log.data;
  inputs.push_back(s.params);
  if (!s.reference.empty()) inputs.push_back(s.reference);
  return finish_report(s.out, std::move(report), inputs);
}

}  // namespace

void add_monitor_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<MonitorSettings>();
  auto* cmd = app.add_subcommand("monitor",
                                 "find contacts in a log with the calibrated model's generalised-momentum observer, or "
                                 "set a drive's collision monitor (docs/monitor.md)");
  s->log.add_to(cmd, false);
  cmd->add_option("--params", s->params, "the calibrated parameter JSON (dyncal identify --params)")->required();
  cmd->add_option("--alarms-per-hour", s->alarms_per_hour,
                  "false alarms per hour the thresholds allow the whole arm on motion like the calibration's")
      ->capture_default_str();
  cmd->add_option("--reference", s->reference,
                  "a log of contact-free motion to take the residual statistics from (default: the parameter "
                  "file's, from the log identify fitted)");
  cmd->add_option("--gain", s->gain,
                  "observer gain K [1/s] with --reference (default: 4 / 20 ms, at most the sample rate)");
  cmd->add_option("--drive", s->drive,
                  "tcp://HOST:PORT or rtu:DEVICE: write the thresholds into this drive's collision monitor "
                  "(instead of --data)");
  add_report_options(cmd, s->out, "monitor", "write thresholds and contacts as JSON");
  cmd->add_option("--plots", s->plots,
                  "write SVG plots (gnuplot) of each joint's residual and threshold, contacts shaded, into this "
                  "directory");
  cmd->callback([s, &run] { run = [s] { return run_monitor(*s); }; });
}

}  // namespace dyncal::app
