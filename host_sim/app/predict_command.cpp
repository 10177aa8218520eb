// dyncal predict: a parameter file (dyncal identify --params) validated on a log it was not fitted to.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_host/identification/reports/identify_report.hpp"
#include "dyncal_host/report/torque_series.hpp"
#include "report_outputs.hpp"

namespace dyncal::app {
namespace {

struct PredictSettings {
  LogOption log;
  host::IdentifyOptions options;
  std::string params, torque_delay;
  ReportOutputs out;
};

int run_predict(PredictSettings& s) {
  prepare_report_outputs(s.out);
  std::vector<std::string> time_shapes;
  const host::ParameterSet p = host::without_time_shapes(host::read_parameter_file(s.params), &time_shapes);
  if (s.log.robot.name.empty()) s.log.robot.name = p.robot;  // the robot the parameters were identified for
  if (s.log.robot.name != p.robot)
    throw host::InputError(s.params + ": parameters are for robot '" + p.robot + "', not '" + s.log.robot.name + "'");
  const auto robot = s.log.load_robot();
  s.options.torque_delays = host::parse_torque_delays(s.torque_delay, robot.num_joints);
  std::vector<std::string> dropped;
  const auto log = s.log.load_log(robot, &dropped);
  host::LogPrediction result = host::predict(robot, log, s.options, p);
  result.notes.insert(result.notes.begin(), time_shapes.begin(), time_shapes.end());
  result.notes.insert(result.notes.begin(), dropped.begin(), dropped.end());
  std::cout << "dyncal predict: robot " << robot.name << ", model " << p.model << ", parameters " << p.source << "\n";
  host::print_log_prediction(std::cout, result);
  if (!s.out.wanted()) return 0;
  nlohmann::json j = host::log_prediction_json(result);
  j["robot"] = robot.name;
  j["model"] = p.model;
  j["params"] = p.source;
  if (s.out.page()) {
    const host::TorqueTrace trace = host::predicted_trace(robot, log, s.options, p);
    j["series"] = host::torque_series_json(trace.t, trace.measured, trace.predicted);
  }
  std::vector<std::string> inputs = s.log.data;
  inputs.push_back(s.params);
  return finish_report(s.out, std::move(j), inputs);
}

}  // namespace

void add_predict_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<PredictSettings>();
  auto* cmd = app.add_subcommand("predict", "predict a log's torque with a parameter file and report the error");
  s->log.add_to(cmd);
  cmd->add_option("--params", s->params, "parameter JSON from dyncal identify --params")->required();
  cmd->add_option("--torque-delay", s->torque_delay,
                  "a torque channel lagging its position channel, undone on the log before the fit: JOINT:SECONDS, "
                  "comma-separated (diagnose reports torque_delay)");
  cmd->add_option("--cutoff", s->options.cutoff_hz, "zero-phase Butterworth cut-off [Hz] (as identify's)")
      ->capture_default_str();
  cmd->add_option("--filter-order", s->options.filter_order, "Butterworth order (even)")->capture_default_str();
  add_report_options(cmd, s->out, "predict", "write the prediction's metrics as JSON");
  cmd->callback([&run, s] { run = [s] { return run_predict(*s); }; });
}

}  // namespace dyncal::app
