// dyncal monitor: contacts in a log found by the generalised-momentum observer of the calibrated
// model, with thresholds from the calibration's own residual statistics (docs/monitor.md).
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/monitoring/contact_monitor.hpp"
#include "dyncal_host/identification/reports/prediction.hpp"

namespace dyncal::app {
namespace {

struct MonitorSettings {
  LogOption log;
  std::string params, reference, report, plots;
  double alarms_per_hour = 0.01;
  double gain = 0;
};

int run_monitor(MonitorSettings& s) {
  const host::ParameterSet params = host::read_parameter_file(s.params);
  if (s.log.robot.name.empty()) s.log.robot.name = params.robot;
  if (s.log.robot.name != params.robot)
    throw host::InputError(s.params + ": parameters are for robot '" + params.robot + "', not '" + s.log.robot.name +
                           "'");
  const auto robot = s.log.load_robot();
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
  if (static_cast<int>(stats.std.size()) != robot.num_joints)
    throw host::InputError(s.params + ": the residual statistics are for " + std::to_string(stats.std.size()) +
                           " joints, the robot has " + std::to_string(robot.num_joints));
  const host::ObserverRun run = host::run_observer(robot, s.log.load_log(robot), params, stats.gain, stats.band);
  if (std::abs(run.period - stats.period) > 0.01 * stats.period)
    throw host::InputError("the log is sampled every " + std::to_string(run.period * 1e3) +
                           " ms, the residual statistics every " + std::to_string(stats.period * 1e3) +
                           " ms: thresholds hold only at the rate they were measured at");
  const std::vector<host::ContactThreshold> thresholds = host::contact_thresholds(stats, s.alarms_per_hour);
  const std::vector<host::Contact> contacts = host::detect_contacts(run, stats, thresholds);

  std::cout << "monitor: generalised-momentum observer, K = " << stats.gain << " 1/s (time constant "
            << std::setprecision(3) << 1e3 / stats.gain << " ms), " << 1.0 / run.period << " Hz\n";
  for (const auto& n : run.notes) std::cout << "note: " << n << "\n";
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
  if (!s.report.empty()) {
    write_json_file(s.report, {{"robot", robot.name},
                               {"data", s.log.data},
                               {"params", s.params},
                               {"alarms_per_hour", s.alarms_per_hour},
                               {"statistics", host::residual_statistics_json(stats)},
                               {"thresholds", threshold_list},
                               {"notes", run.notes},
                               {"contacts", list}});
  }
  return 0;
}

}  // namespace

void add_monitor_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<MonitorSettings>();
  auto* cmd = app.add_subcommand(
      "monitor", "find contacts in a log with the calibrated model's generalised-momentum observer (docs/monitor.md)");
  s->log.add_to(cmd);
  cmd->add_option("--params", s->params, "the calibrated parameter JSON (dyncal identify --params)")->required();
  cmd->add_option("--alarms-per-hour", s->alarms_per_hour,
                  "false alarms per hour the thresholds allow the whole arm on motion like the calibration's")
      ->capture_default_str();
  cmd->add_option("--reference", s->reference,
                  "a log of contact-free motion to take the residual statistics from (default: the parameter "
                  "file's, from the log identify fitted)");
  cmd->add_option("--gain", s->gain,
                  "observer gain K [1/s] with --reference (default: 4 / 20 ms, at most the sample rate)");
  cmd->add_option("--report", s->report, "write thresholds and contacts as JSON");
  cmd->add_option("--plots", s->plots,
                  "write SVG plots (gnuplot) of each joint's residual and threshold, contacts shaded, into this "
                  "directory");
  cmd->callback([s, &run] { run = [s] { return run_monitor(*s); }; });
}

}  // namespace dyncal::app
