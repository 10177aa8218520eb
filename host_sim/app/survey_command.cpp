// dyncal survey: the survey's simulation study (survey::kStudyRobot's arm), beside its published numbers.
#include <iostream>
#include <map>
#include <memory>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/survey/compare_survey.hpp"
#include "dyncal_host/survey/print_survey.hpp"
#include "dyncal_host/survey/run_survey.hpp"
#include "dyncal_host/survey/survey_plots.hpp"
#include "entry_points.hpp"

namespace dyncal::app {
namespace {

namespace survey = host::survey;

struct SurveySettings {
  std::string robots_dir, json, check, plots, from_json;
  survey::SurveyOptions options;
  double tolerance = 1e-3;
};

int run_survey(const SurveySettings& s) {
  const auto robot = host::load_robot(s.robots_dir, survey::kStudyRobot);
  const nlohmann::json published = read_json_file(robot.directory + "/survey_published.json");
  survey::SurveySeries series;
  if (!s.from_json.empty() && !s.plots.empty())
    throw host::InputError("survey: --plots needs the run's time series; it cannot take --from-json");
  const nlohmann::json result = s.from_json.empty()
                                    ? survey::run_survey(robot, s.options, s.plots.empty() ? nullptr : &series)
                                    : read_json_file(s.from_json);
  if (!s.json.empty()) write_json_file(s.json, result, "survey results");
  survey::print_survey(std::cout, result, published);
  if (!s.plots.empty()) {
    const std::vector<std::string> files = survey::write_survey_plots(result, series, s.plots);
    std::cout << "\nplots (" << files.size() << " SVG files) in " << s.plots << "\n";
  }
  if (s.check.empty()) return 0;
  const std::string diff = survey::compare_survey(result, read_json_file(s.check), s.tolerance);
  if (!diff.empty()) {
    std::cerr << "dyncal survey: differs from " << s.check << ":\n" << diff;
    return 1;
  }
  std::cout << "\nmatches " << s.check << " (relative tolerance " << s.tolerance << ")\n";
  return 0;
}

}  // namespace

void add_survey_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<SurveySettings>();
  s->robots_dir = host::default_robots_dir();
  auto* cmd = app.add_subcommand("survey", kSurveyHelp);
  cmd->add_option("--robots-dir", s->robots_dir, "directory holding the robot descriptions");
  cmd->add_flag("--quick", s->options.quick, "one excitation period instead of two (CI)");
  cmd->add_option("--seed", s->options.seed, "excitation, noise and CAD-prior seed")->capture_default_str();
  cmd->add_option("--prior-on", s->options.prior_on,
                  "which set values the CAD prior's errors are drawn on: table5 (mass, centre of mass, inertia "
                  "about it, as CAD reports them) or standard (inertia about the link frame, first moments)")
      ->transform(
          CLI::CheckedTransformer(std::map<std::string, host::PriorErrors>{{"table5", host::PriorErrors::table5},
                                                                           {"standard", host::PriorErrors::standard}},
                                  CLI::ignore_case))
      ->capture_default_str();
  cmd->add_option("--prior-error", s->options.prior_error, "CAD prior: relative error of every set value (uniform)")
      ->capture_default_str();
  cmd->add_option("--jobs", s->options.jobs,
                  "threads for the study's independent runs (0: one per hardware thread; the results do not depend "
                  "on it, the solution times may)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--json", s->json, "write the results as JSON");
  cmd->add_option("--from-json", s->from_json,
                  "print the tables of a result written by --json instead of running the study");
  cmd->add_option("--plots", s->plots,
                  "write Fig. 2 (the designed excitation), Fig. 4 (following beta) and the residual per joint and "
                  "method as SVG into this directory (gnuplot)");
  cmd->add_option("--check", s->check, "compare with a committed result JSON; exit 1 on any difference");
  cmd->add_option("--tolerance", s->tolerance, "relative tolerance of --check")->capture_default_str();
  cmd->callback([&run, s] { run = [s] { return run_survey(*s); }; });
}

int run_dyncal_survey(int argc, char** argv) {
  return run_cli(add_survey_command, argc, argv);
}

}  // namespace dyncal::app
