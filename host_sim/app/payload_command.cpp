// dyncal payload: the load on the last link identified from a log with it, the arm's calibrated
// parameters fixed (docs/payload.md).
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/payload/payload.hpp"
#include "dyncal_host/identification/reports/prediction.hpp"

namespace dyncal::app {
namespace {

struct PayloadSettings {
  LogOption log;
  host::IdentifyOptions options;
  std::string params, report, save_params;
};

int run_payload(PayloadSettings& s) {
  const host::ParameterSet arm = host::read_parameter_file(s.params);
  if (s.log.robot.name.empty()) s.log.robot.name = arm.robot;
  if (s.log.robot.name != arm.robot)
    throw host::InputError(s.params + ": parameters are for robot '" + arm.robot + "', not '" + s.log.robot.name + "'");
  const auto robot = s.log.load_robot();
  std::vector<std::string> dropped;
  const auto log = s.log.load_log(robot, &dropped);
  host::PayloadResult r = host::identify_payload(robot, log, arm, s.options);
  r.notes.insert(r.notes.begin(), dropped.begin(), dropped.end());
  host::print_payload_report(std::cout, r);
  if (!s.report.empty()) write_json_file(s.report, host::payload_report_json(r));
  if (!s.save_params.empty()) {
    const host::ParameterSet loaded = host::with_payload(arm, robot, r.standard);
    write_json_file(s.save_params, host::loaded_parameter_file_json(loaded, r));
    std::cout << "loaded model written to " << s.save_params << " (the arm's parameters with the payload on link "
              << r.link << ")\n";
  }
  return 0;
}

}  // namespace

void add_payload_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<PayloadSettings>();
  auto* cmd = app.add_subcommand("payload",
                                 "identify the load on the last link from a log with it, the arm's parameters fixed");
  s->log.add_to(cmd);
  cmd->add_option("--params", s->params, "the arm's parameter JSON (dyncal identify --params), without the load")
      ->required();
  cmd->add_option("--cutoff", s->options.cutoff_hz, "zero-phase Butterworth cut-off [Hz] (as identify's)")
      ->capture_default_str();
  cmd->add_option("--filter-order", s->options.filter_order, "Butterworth order (even)")->capture_default_str();
  cmd->add_option("--report", s->report, "write the payload and its verdicts as JSON");
  cmd->add_option("--save-params", s->save_params,
                  "write the loaded arm's parameter file (predict, flash, table and diagnose take it)");
  cmd->callback([&run, s] { run = [s] { return run_payload(*s); }; });
}

}  // namespace dyncal::app
