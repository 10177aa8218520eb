// dyncal: the command-line tool.
#include <CLI/CLI.hpp>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <map>

#include "drive_commands.hpp"
#include "dyncal_host/diagnose.hpp"
#include "dyncal_host/excite.hpp"
#include "dyncal_host/friction_comparison.hpp"
#include "dyncal_host/identify.hpp"
#include "dyncal_host/identify_report.hpp"
#include "dyncal_host/input_error.hpp"
#include "dyncal_host/joint_log.hpp"
#include "dyncal_host/robot_description.hpp"
#include "dyncal_host/survey/survey.hpp"

namespace {

void write_json(const std::string& path, const nlohmann::json& j) {
  std::ofstream out(path);
  if (!out) throw dyncal::host::InputError("cannot write '" + path + "'");
  out << j.dump(2) << "\n";
}

nlohmann::json read_json(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw dyncal::host::InputError("cannot read '" + path + "'");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw dyncal::host::InputError(path + ": invalid JSON: " + e.what());
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"dyncal: dynamic calibration of six-axis robot arms"};
  app.require_subcommand(1);

  std::string robot_name, format = "csv", data, model = "eq7,rotor_inertia,offset", report, params;
  std::string robots_dir = dyncal::host::default_robots_dir();
  dyncal::host::IdentifyOptions opt;
  auto* identify = app.add_subcommand("identify", "identify base parameters and friction from a measured log");
  identify->add_option("--robot", robot_name, "robot name (robots/<name>/); tx40 by default with --format tx40");
  identify->add_option("--robots-dir", robots_dir, "directory holding the robot descriptions");
  identify->add_option("--format", format, "log format: csv (t,q1..qN,[qd..],[qdd..],tau1..tauN) or tx40")
      ->check(CLI::IsMember({"csv", "tx40"}));
  identify->add_option("--data", data, "CSV log file, or the folder of the TX40 files")->required();
  identify
      ->add_option("--model", model,
                   "terms besides the rigid body: eq7|eq8|coulomb|viscous|power|rotor_inertia|offset, comma-separated")
      ->capture_default_str();
  identify->add_option("--method", opt.method, "ols | wls | kf | rls")
      ->check(CLI::IsMember({"ols", "wls", "kf", "rls"}))
      ->capture_default_str();
  identify->add_option("--cutoff", opt.cutoff_hz, "zero-phase Butterworth cut-off [Hz]")->capture_default_str();
  identify->add_option("--filter-order", opt.filter_order, "Butterworth order (even)")->capture_default_str();
  identify->add_option("--decimate", opt.decimate, "decimation factor (0: automatic, about 25 x cut-off)")
      ->capture_default_str();
  identify->add_option("--folds", opt.folds, "folds of the blocked cross-validation")->capture_default_str();
  identify->add_option("--block", opt.block_seconds, "cross-validation block length [s]")->capture_default_str();
  identify->add_option("--validate-last", opt.validate_last, "validate on this final fraction instead (time split)");
  identify->add_option("--mu", opt.rls_mu, "RLS forgetting factor mu (survey Eq. 23)")->capture_default_str();
  identify->add_option("--p0", opt.p0, "KF/RLS initial covariance diagonal")->capture_default_str();
  identify
      ->add_option("--min-speed", opt.min_speed_fraction,
                   "fit only rows where |qd_j| >= this fraction of joint j's top speed (stiction)")
      ->capture_default_str();
  identify->add_option("--report", report, "write the report as JSON");
  identify->add_option("--params", params, "write the identified parameter table as JSON");
  bool compare_friction = false;
  identify->add_flag("--compare-friction", compare_friction,
                     "fit each friction model (survey Eq. 4-9) with the --model's other terms and compare their "
                     "torque error on the fitted part and on the last --validate-last (default 0.3) of the log "
                     "(survey Table 12)");

  std::string diag_model = "eq7", diag_report;
  dyncal::host::DiagnoseOptions dopt;
  auto* diagnose =
      app.add_subcommand("diagnose", "find what the declared model lacks in a measured log, add it, report");
  diagnose->add_option("--robot", robot_name, "robot name; tx40 by default with --format tx40");
  diagnose->add_option("--robots-dir", robots_dir, "directory holding the robot descriptions");
  diagnose->add_option("--format", format, "log format: csv or tx40")->check(CLI::IsMember({"csv", "tx40"}));
  diagnose->add_option("--data", data, "CSV log file, or the folder of the TX40 files")->required();
  diagnose->add_option("--model", diag_model, "declared model: eq7 or eq8, optionally with rotor_inertia and offset")
      ->capture_default_str();
  diagnose->add_option("--cutoff", dopt.identify.cutoff_hz, "zero-phase Butterworth cut-off [Hz]")
      ->capture_default_str();
  diagnose->add_option("--max-effects", dopt.max_effects, "greedy steps at most")->capture_default_str();
  diagnose->add_option("--bic", dopt.bic_threshold, "BIC drop an effect needs")->capture_default_str();
  diagnose->add_option("--report", diag_report, "write the report as JSON");
  std::string diag_plots;
  diagnose->add_option("--plots", diag_plots, "write SVG plots (gnuplot) into this directory");

  dyncal::host::ExciteOptions xopt;
  std::string excite_out, excite_criterion = "cond", excite_model = "eq7", excite_robot = "er20";
  auto* excite = app.add_subcommand(
      "excite", "design an excitation trajectory (Fourier series, Eq. 27) minimising cond(K) (Eq. 26) or -log det");
  excite->add_option("--robot", excite_robot, "robot (er20, tx40)")->capture_default_str();
  excite->add_option("--robots-dir", robots_dir, "directory holding the robot descriptions");
  excite->add_option("--omega-f", xopt.f_f, "fundamental frequency [Hz]")->capture_default_str();
  excite->add_option("--harmonics", xopt.harmonics, "L")->capture_default_str();
  excite->add_option("--criterion", excite_criterion, "cond | logdet")
      ->check(CLI::IsMember({"cond", "logdet"}))
      ->capture_default_str();
  excite
      ->add_option("--model", excite_model, "K of eq7 (linear friction) or eq4 (Stribeck, at the robot file's values)")
      ->check(CLI::IsMember({"eq7", "eq4"}))
      ->capture_default_str();
  excite->add_option("--margin", xopt.margin, "fraction of every limit the motion may use")->capture_default_str();
  excite->add_option("--candidates", xopt.candidates, "random starts; the best is optimised")->capture_default_str();
  excite->add_option("--evaluations", xopt.max_evaluations, "criterion evaluations")->capture_default_str();
  excite->add_option("--seed", xopt.seed, "seed of the random starts")->capture_default_str();
  excite->add_option("--out", excite_out, "trajectory file to write (JSON; dyncal calibrate --trajectory)")->required();

  dyncal::host::survey::SurveyOptions sopt;
  std::string survey_json, survey_check;
  double survey_tolerance = 1e-3;
  auto* survey = app.add_subcommand(
      "survey", "reproduce the survey's simulation study on the er20 (Tables 5, 6, 8-12, Fig. 4) next to its numbers");
  survey->add_option("--robots-dir", robots_dir, "directory holding the robot descriptions");
  survey->add_flag("--quick", sopt.quick, "one excitation period instead of two (CI)");
  survey->add_option("--seed", sopt.seed, "excitation, noise and CAD-prior seed")->capture_default_str();
  survey
      ->add_option("--prior-on", sopt.prior_on,
                   "which set values the CAD prior's errors are drawn on: table5 (mass, centre of mass, inertia "
                   "about it, as CAD reports them) or standard (inertia about the link frame, first moments)")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, dyncal::host::survey::PriorErrors>{
              {"table5", dyncal::host::survey::PriorErrors::table5},
              {"standard", dyncal::host::survey::PriorErrors::standard}},
          CLI::ignore_case))
      ->capture_default_str();
  survey->add_option("--prior-error", sopt.prior_error, "CAD prior: relative error of every set value (uniform)")
      ->capture_default_str();
  survey->add_option("--json", survey_json, "write the results as JSON");
  survey->add_option("--check", survey_check, "compare with a committed result JSON; exit 1 on any difference");
  survey->add_option("--tolerance", survey_tolerance, "relative tolerance of --check")->capture_default_str();

  std::function<int()> run;
  add_drive_commands(app, run, robots_dir);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  try {
    if (run) return run();
    if (app.got_subcommand(excite)) {
      const auto robot = dyncal::host::load_robot(robots_dir, excite_robot);
      xopt.criterion = excite_criterion == "logdet" ? dyncal::host::ExcitationCriterion::logdet
                                                    : dyncal::host::ExcitationCriterion::cond;
      xopt.model = excite_model == "eq4" ? dyncal::host::FrictionModel::eq4 : dyncal::host::FrictionModel::eq7;
      const auto r = dyncal::host::design_excitation(robot, xopt);
      nlohmann::json j = dyncal::host::trajectory_to_json(robot, r.trajectory);
      j["design"] = {
          {"criterion", excite_criterion}, {"model", excite_model},        {"cond", r.cond},       {"logdet", r.logdet},
          {"start_cond", r.start_cond},    {"evaluations", r.evaluations}, {"margin", xopt.margin}};
      write_json(excite_out, j);
      std::cout << std::fixed << std::setprecision(2) << "excitation for " << robot.name
                << ": Eq. 27, L = " << xopt.harmonics << ", f_f = " << xopt.f_f << " Hz, K of " << excite_model
                << ", columns unit-scaled\n"
                << "cond(K): best of " << xopt.candidates << " random starts " << r.start_cond << " -> optimised "
                << r.cond << " (" << excite_criterion << ", " << r.evaluations << " evaluations); log det " << r.logdet
                << "\n"
                << "joint   position   velocity   acceleration   (fraction of the limit)\n";
      for (int i = 0; i < 6; ++i) {
        std::cout << std::setw(5) << i + 1 << std::setw(11) << r.position_use[static_cast<size_t>(i)] << std::setw(11)
                  << r.velocity_use[static_cast<size_t>(i)] << std::setw(15)
                  << r.acceleration_use[static_cast<size_t>(i)] << "\n";
      }
      std::cout << "written to " << excite_out << "\n";
      return 0;
    }
    if (app.got_subcommand(survey)) {
      const auto robot = dyncal::host::load_robot(robots_dir, "er20");
      const nlohmann::json published = read_json(robots_dir + "/er20/survey_published.json");
      const nlohmann::json result = dyncal::host::survey::run_survey(robot, sopt);
      if (!survey_json.empty()) write_json(survey_json, result);
      dyncal::host::survey::print_survey(std::cout, result, published);
      if (!survey_check.empty()) {
        const std::string diff =
            dyncal::host::survey::compare_survey(result, read_json(survey_check), survey_tolerance);
        if (!diff.empty()) {
          std::cerr << "dyncal survey: differs from " << survey_check << ":\n" << diff;
          return 1;
        }
        std::cout << "\nmatches " << survey_check << " (relative tolerance " << survey_tolerance << ")\n";
      }
      return 0;
    }
    if (app.got_subcommand(diagnose)) {
      if (robot_name.empty()) {
        if (format != "tx40") throw dyncal::host::InputError("--robot is required for --format csv");
        robot_name = "tx40";
      }
      const auto robot = dyncal::host::load_robot(robots_dir, robot_name);
      dopt.identify.terms = dyncal::host::parse_model(diag_model);
      const auto log = format == "tx40" ? dyncal::host::read_tx40_log(data, robot.transmission, robot.joint_offsets)
                                        : dyncal::host::read_csv_log(data, robot.num_joints);
      const auto result = dyncal::host::diagnose(robot, log, dopt);
      dyncal::host::print_diagnose_report(std::cout, result);
      if (!diag_report.empty()) write_json(diag_report, dyncal::host::diagnose_report_json(result));
      if (!diag_plots.empty()) {
        const auto files = dyncal::host::write_diagnose_plots(result, diag_plots);
        std::cout << "\nplots: " << files.size() << " SVG files in " << diag_plots << "\n";
      }
      return 0;
    }
    if (app.got_subcommand(identify)) {
      if (robot_name.empty()) {
        if (format != "tx40") throw dyncal::host::InputError("--robot is required for --format csv");
        robot_name = "tx40";
      }
      const auto robot = dyncal::host::load_robot(robots_dir, robot_name);
      opt.terms = dyncal::host::parse_model(model);
      const auto log = format == "tx40" ? dyncal::host::read_tx40_log(data, robot.transmission, robot.joint_offsets)
                                        : dyncal::host::read_csv_log(data, robot.num_joints);
      if (compare_friction) {
        const double last = opt.validate_last > 0 ? opt.validate_last : 0.3;
        const auto stacked = dyncal::host::prepare_stacked(robot, log, opt);
        dyncal::host::print_friction_comparison(std::cout, dyncal::host::compare_friction_models(stacked, last), last);
        return 0;
      }
      const auto result = dyncal::host::identify(robot, log, opt);
      dyncal::host::print_identify_report(std::cout, result);
      if (!report.empty()) write_json(report, dyncal::host::identify_report_json(result));
      if (!params.empty()) write_json(params, dyncal::host::parameter_table_json(result));
    }
  } catch (const dyncal::host::InputError& e) {
    std::cerr << "dyncal: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "dyncal: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
