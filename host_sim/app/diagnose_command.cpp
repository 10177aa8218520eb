// dyncal diagnose: what the declared model lacks in a measured log, added and reported.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "dyncal_host/diagnosis/diagnose.hpp"
#include "dyncal_host/report/torque_series.hpp"
#include "report_outputs.hpp"

namespace dyncal::app {
namespace {

struct DiagnoseSettings {
  LogOption log;
  host::DiagnoseOptions options;
  std::string model = "eq7,rotor_inertia,offset", plots;  // identify's default model
  std::string torque_delay;
  ReportOutputs out;
};

int run_diagnose(DiagnoseSettings& s) {
  prepare_report_outputs(s.out);
  const auto robot = s.log.load_robot();
  const host::ModelSpec spec = host::parse_model_spec(s.model, robot.num_joints);
  s.options.identify.terms = spec.terms;
  s.options.identify.effects = spec.effects;
  s.options.identify.motors = spec.motors;
  s.options.identify.torque_delays = host::parse_torque_delays(s.torque_delay, robot.num_joints);
  std::vector<std::string> dropped;
  const auto log = s.log.load_log(robot, &dropped);
  auto result = host::diagnose(robot, log, s.options);
  result.notes.insert(result.notes.begin(), dropped.begin(), dropped.end());
  host::print_diagnose_report(std::cout, result);
  if (!s.plots.empty()) {
    const auto files = host::write_diagnose_plots(result, s.plots);
    std::cout << "\nplots: " << files.size() << " SVG files in " << s.plots << "\n";
  }
  if (!s.out.wanted()) return 0;
  nlohmann::json report = host::diagnose_report_json(result);
  if (s.out.page()) {  // the torque, the declared model's prediction and the one with the effects found
    const auto& tr = result.traces;
    report["series"] = host::torque_series_json(tr.t, tr.tau, tr.tau_before, &tr.tau_after);
  }
  return finish_report(s.out, std::move(report), s.log.data);
}

}  // namespace

void add_diagnose_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<DiagnoseSettings>();
  auto* cmd = app.add_subcommand("diagnose", "find what the declared model lacks in a measured log, add it, report");
  s->log.add_to(cmd);
  cmd->add_option("--torque-delay", s->torque_delay,
                  "a torque channel lagging its position channel, undone on the log before the fit: JOINT:SECONDS, "
                  "comma-separated (diagnose reports torque_delay)");
  cmd->add_option("--model", s->model,
                  "declared model, identify's vocabulary: eq7 or eq8, optionally rotor_inertia and offset, and effect "
                  "items KIND:JOINT[:SHAPE] (docs/cli.md)")
      ->capture_default_str();
  cmd->add_option("--method", s->options.identify.method,
                  "wls: each joint's rows weighted by 1 / its residual noise under the declared model (Gautier); ols: "
                  "unweighted")
      ->check(CLI::IsMember({"wls", "ols"}))
      ->capture_default_str();
  cmd->add_option("--cutoff", s->options.identify.cutoff_hz, "zero-phase Butterworth cut-off [Hz]")
      ->capture_default_str();
  cmd->add_option("--max-effects", s->options.max_effects, "greedy steps at most")->capture_default_str();
  cmd->add_flag("--friction-per-joint", s->options.identify.friction_per_joint,
                "friction and rotor inertia per joint, ignoring a coupling robot.json's transmission declares (so "
                "that the diagnosis can find it)");
  cmd->add_option("--bic", s->options.bic_threshold, "BIC drop an effect needs")->capture_default_str();
  add_report_options(cmd, s->out, "diagnose", "write the report as JSON");
  cmd->add_option("--plots", s->plots, "write SVG plots (gnuplot) into this directory");
  cmd->callback([&run, s] { run = [s] { return run_diagnose(*s); }; });
}

}  // namespace dyncal::app
