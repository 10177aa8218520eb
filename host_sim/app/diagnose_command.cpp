// dyncal diagnose: what the declared model lacks in a measured log, added and reported.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "dyncal_host/diagnosis/diagnose.hpp"

namespace dyncal::app {
namespace {

struct DiagnoseSettings {
  LogOption log;
  host::DiagnoseOptions options;
  std::string model = "eq7,rotor_inertia,offset", report, plots;  // identify's default model
};

int run_diagnose(DiagnoseSettings& s) {
  check_outputs({{s.report, "report"}});
  const auto robot = s.log.load_robot();
  const host::ModelSpec spec = host::parse_model_spec(s.model, robot.num_joints);
  s.options.identify.terms = spec.terms;
  s.options.identify.effects = spec.effects;
  s.options.identify.motors = spec.motors;
  std::vector<std::string> dropped;
  const auto log = s.log.load_log(robot, &dropped);
  auto result = host::diagnose(robot, log, s.options);
  result.notes.insert(result.notes.begin(), dropped.begin(), dropped.end());
  host::print_diagnose_report(std::cout, result);
  if (!s.report.empty()) write_json_file(s.report, host::diagnose_report_json(result), "report");
  if (!s.plots.empty()) {
    const auto files = host::write_diagnose_plots(result, s.plots);
    std::cout << "\nplots: " << files.size() << " SVG files in " << s.plots << "\n";
  }
  return 0;
}

}  // namespace

void add_diagnose_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<DiagnoseSettings>();
  auto* cmd = app.add_subcommand("diagnose", "find what the declared model lacks in a measured log, add it, report");
  s->log.add_to(cmd);
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
  cmd->add_option("--report", s->report, "write the report as JSON");
  cmd->add_option("--plots", s->plots, "write SVG plots (gnuplot) into this directory");
  cmd->callback([&run, s] { run = [s] { return run_diagnose(*s); }; });
}

}  // namespace dyncal::app
