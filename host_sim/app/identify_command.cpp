// dyncal identify: base parameters and friction from a measured log, cross-validated.
#include <algorithm>
#include <iostream>
#include <limits>
#include <memory>
#include <utility>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/drive/closed_loop.hpp"
#include "dyncal_host/identification/methods/friction_comparison.hpp"
#include "dyncal_host/identification/pipeline/drive_law.hpp"
#include "dyncal_host/identification/pipeline/identify.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_host/identification/reports/identify_report.hpp"
#include "dyncal_host/model/stacked_data.hpp"
#include "dyncal_host/monitoring/contact_monitor.hpp"
#include "dyncal_host/payload/torque_constants.hpp"
#include "dyncal_host/report/torque_series.hpp"
#include "report_outputs.hpp"

namespace dyncal::app {
namespace {

struct IdentifySettings {
  LogOption log;
  host::IdentifyOptions options;
  std::string model = "eq7,rotor_inertia,offset", params, effects, law, torque_delay;
  ReportOutputs out;
  std::vector<std::string> validate_on;
  bool compare_friction = false;
  std::vector<std::string> loaded;  ///< --loaded-data: the known-load run of a current-logging arm
  double load_mass = 0;
  std::vector<double> load_com;
};

/// --loaded-data: each motor's Kt from the loaded and unloaded current logs (torque_constants.hpp),
/// printed (and kept for the report); returns the robot with them in place of robot.json's.
host::RobotDescription torque_constants_from_load(const IdentifySettings& s, const host::RobotDescription& robot,
                                                  nlohmann::json* report, Eigen::VectorXd* kt_std) {
  if (s.log.torque_from != "current")
    throw host::InputError("--loaded-data identifies the motors' torque constants: it needs --torque-from current");
  if (!(s.load_mass > 0)) throw host::InputError("--loaded-data needs --load-mass (the load's mass [kg], > 0)");
  host::KnownLoad load;
  load.mass = s.load_mass;
  if (!s.load_com.empty()) {
    load.com_known = true;
    load.com = Eigen::Vector3d(s.load_com[0], s.load_com[1], s.load_com[2]);
  }
  // The currents through the transmission (every Kt 1); they have no rating to be checked against
  // before Kt is known (the unloaded log is checked again with the identified Kt below).
  host::RobotDescription unit = robot;
  unit.torque_constants = Eigen::VectorXd::Ones(robot.num_joints);
  unit.tau_max = Eigen::VectorXd::Constant(robot.num_joints, std::numeric_limits<double>::infinity());
  const host::JointLog unloaded = s.log.load_log(unit);
  const host::JointLog loaded = s.log.load_logs(unit, s.loaded);
  const host::TorqueConstantFit fit = host::identify_torque_constants(robot, unloaded, loaded, load, s.options);
  host::print_torque_constants(std::cout, fit);
  if (!fit.all_determined())
    throw host::InputError(
        "--loaded-data: the pair does not determine every motor's Kt (table above): load the "
        "arm so that each joint carries the load's weight or inertia, or declare those Kt in "
        "robot.json");
  std::cout << "identify goes on with these Kt; put them into " << robot.directory
            << "/robot.json's transmission.torque_constants to keep them\n\n";
  *report = host::torque_constants_json(fit);
  *kt_std = fit.stdev;
  host::RobotDescription out = robot;
  out.torque_constants = fit.kt;
  return out;
}

/// --effects: a diagnosis report's effects join the model `spec`; one the model already has is not
/// added twice. Its torque delays are undone on the log, unless --torque-delay gives that joint's.
/// What is left out is named in `dropped`.
void merge_diagnosed_effects(IdentifySettings& s, int num_joints, host::ModelSpec& spec,
                             std::vector<std::string>& dropped) {
  std::vector<std::string> skipped;
  std::vector<host::TorqueDelay> delays;
  const host::ModelSpec found = host::read_diagnosed_effects(s.effects, num_joints, &skipped, &delays);
  for (const host::TorqueDelay& d : delays) {
    if (std::any_of(s.options.torque_delays.begin(), s.options.torque_delays.end(),
                    [&](const host::TorqueDelay& o) { return o.joint == d.joint; }))
      dropped.push_back(s.effects + ": torque_delay on joint " + std::to_string(d.joint + 1) +
                        ": --torque-delay gives that joint's");
    else
      s.options.torque_delays.push_back(d);
  }
  for (const auto& e : found.effects) {
    if (host::model_contains(spec, e))
      dropped.push_back(s.effects + ": " + host::effect_item(e) + " is already in the model");
    else
      host::add_effect(spec, e, s.effects);
  }
  for (const auto& m : found.motors) {
    if (std::any_of(spec.motors.begin(), spec.motors.end(), [&](const auto& o) { return o.motor == m.motor; }))
      dropped.push_back(s.effects + ": " + host::coupled_motor_item(m) + ": the model couples that motor already");
    else
      spec.motors.push_back(m);
  }
  for (const auto& k : skipped) dropped.push_back(s.effects + ": " + k);
}

int run_identify(IdentifySettings& s) {
  prepare_report_outputs(s.out);
  check_outputs({{s.params, "parameters"}});
  auto robot = s.log.load_robot();
  std::vector<std::string> dropped;
  host::ModelSpec spec = host::parse_model_spec(s.model, robot.num_joints);
  s.options.torque_delays = host::parse_torque_delays(s.torque_delay, robot.num_joints);
  if (!s.effects.empty()) merge_diagnosed_effects(s, robot.num_joints, spec, dropped);
  s.options.terms = spec.terms;
  s.options.effects = spec.effects;
  s.options.motors = spec.motors;
  if (!s.law.empty()) {
    if (s.options.method != "iv") throw host::InputError("--law is the control law of --method iv");
    const auto law = std::make_shared<host::DriveLaw>(host::read_drive_law(s.law, robot));
    s.options.closed_loop = [robot, law](const host::JointLog& grid, const Eigen::VectorXd& phi,
                                         const Eigen::VectorXd& Fc, const Eigen::VectorXd& Fv) {
      host::JointLog out;  // the law's run on the grid's times (drive/closed_loop.hpp)
      out.t = grid.t;
      out.segment_starts = grid.segment_starts;
      out.period = grid.period;
      out.q = host::play_law(robot, *law, grid.t, phi, Fc, Fv);
      out.tau = Eigen::MatrixXd::Zero(grid.t.size(), robot.num_joints);
      return out;
    };
  }
  nlohmann::json torque_constants;
  Eigen::VectorXd kt_std;
  if (!s.loaded.empty()) robot = torque_constants_from_load(s, robot, &torque_constants, &kt_std);
  auto log = s.log.load_log(robot, &dropped);
  if (s.compare_friction) {
    if (!s.options.effects.empty())
      throw host::InputError("--compare-friction compares the friction models of the declared terms, without effects");
    for (const auto& line : dropped) std::cout << "note: " << line << "\n";
    const double last = s.options.validate_last > 0 ? s.options.validate_last : 0.3;
    const auto stacked = host::prepare_stacked(robot, log, s.options);
    for (const auto& line : stacked.notes) std::cout << "note: " << line << "\n";
    host::print_friction_comparison(std::cout, host::compare_friction_models(stacked, last), last);
    return 0;
  }
  // Other logs read (and refused) before any work on the fit.
  std::vector<host::JointLog> others;
  for (const auto& path : s.validate_on) others.push_back(s.log.load_logs(robot, {path}, &dropped));
  auto result = host::identify(robot, std::move(log), s.options);
  result.notes.insert(result.notes.begin(), dropped.begin(), dropped.end());
  host::ParameterSet fitted = host::parameter_set(result);
  if (s.log.torque_from == "current") {  // the constants the currents were converted with go with the set
    fitted.torque_constants = robot.torque_constants;
    fitted.torque_constants_std =
        kt_std.size() > 0 ? kt_std
                          : Eigen::VectorXd::Constant(robot.num_joints, std::numeric_limits<double>::quiet_NaN());
    fitted.torque_constants_source =
        kt_std.size() > 0 ? "fitted from a known load (--loaded-data, --load-mass)" : "robot.json (nominal, no std)";
  }
  for (const auto& other : others) {
    std::vector<std::string> time_shapes;
    result.other_logs.push_back(
        host::predict(robot, other, s.options, host::without_time_shapes(fitted, &time_shapes)));
    result.other_logs.back().notes.insert(result.other_logs.back().notes.end(), time_shapes.begin(), time_shapes.end());
  }
  host::print_identify_report(std::cout, result);
  nlohmann::json report;
  if (s.out.wanted()) {
    report = host::identify_report_json(result);
    host::add_cad_values(report, robot.name);
    if (!torque_constants.is_null()) report["torque_constants"] = torque_constants;
    if (s.out.page()) {  // the fitted log's torque and the final fit's prediction; the log is read again
      const host::TorqueTrace trace = host::predicted_trace(robot, s.log.load_log(robot), s.options, fitted);
      report["series"] = host::torque_series_json(trace.t, trace.measured, trace.predicted);
    }
  }
  if (!s.params.empty()) {
    nlohmann::json file = host::parameter_table_json(result);
    if (fitted.torque_constants.size() > 0) file["torque_constants"] = host::torque_constants_json(fitted);
    // The observer's residual statistics on the fitted log (contact-free: a calibration run), for
    // dyncal monitor's thresholds (docs/monitor.md); the log is read again (identify consumed it).
    try {
      const host::ObserverRun run = host::run_observer(robot, s.log.load_log(robot), fitted);
      file["monitor"] = host::residual_statistics_json(host::residual_statistics(run, s.log.data.front()));
    } catch (const host::InputError& e) {
      std::cout << "note: no contact-detection statistics in " << s.params << ": " << e.what() << "\n";
    }
    write_json_file(s.params, file, "parameters");
  }
  if (!s.out.wanted()) return 0;
  std::vector<std::string> inputs = s.log.data;
  inputs.insert(inputs.end(), s.validate_on.begin(), s.validate_on.end());
  return finish_report(s.out, std::move(report), inputs);
}

}  // namespace

void add_identify_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<IdentifySettings>();
  host::IdentifyOptions& opt = s->options;
  auto* cmd = app.add_subcommand("identify", "identify base parameters and friction from a measured log");
  s->log.add_to(cmd);
  cmd->add_option(
         "--model", s->model,
         "terms besides the rigid body, comma-separated: eq7|eq8|coulomb|viscous|power|rotor_inertia|offset, and "
         "the effects diagnose adds, KIND:JOINT[:SHAPE]: stribeck:J:qds, asymmetric_friction:J, "
         "velocity_power:J, load_friction:J, rotor_inertia:J, offset:J, position_periodic:J:cycles, "
         "coupling:I+J or coupling:I-J (docs/cli.md)")
      ->capture_default_str();
  cmd->add_option("--effects", s->effects,
                  "add the effects of a dyncal diagnose --report file to the model (any method but kf and rls); "
                  "its torque delays are undone on the log");
  cmd->add_option("--torque-delay", s->torque_delay,
                  "a torque channel lagging its position channel, undone on the log before the fit: JOINT:SECONDS, "
                  "comma-separated (diagnose reports torque_delay)");
  cmd->add_option(
         "--method", opt.method,
         "wls: weighted least squares, each joint's rows weighted by 1 / its residual noise (Gautier); ols: "
         "unweighted (the survey's IDIM-OLS); kf: Kalman filter (Eq. 19); rls: forgetting (Eq. 23); pcls: "
         "physically consistent WLS, every link's pseudo-inertia positive definite, robot.json's inertials "
         "as prior (Wensing et al.); gd, ga, pf: the survey's optimisers (gradient descent, genetic "
         "algorithm, particle filter) on the weighted data, every link's pseudo-inertia positive definite, "
         "the inertials searched within --range-width of robot.json's, no prior; iv: IDIM-IV (Eq. 17), instruments "
         "from closed-loop simulations of the --law the log was recorded under, --model eq7 (docs/cli.md)")
      ->check(CLI::IsMember({"wls", "ols", "kf", "rls", "pcls", "gd", "ga", "pf", "iv"}))
      ->capture_default_str();
  cmd->add_option("--law", s->law,
                  "iv: the drive's control law the log was recorded under (JSON: trajectory, periods, sample_rate_hz, "
                  "kp, kd, optional control_rate_hz and feed_forward; docs/cli.md)");
  cmd->add_option("--prior-std", opt.prior_std,
                  "the prior on robot.json's inertials: each standard parameter's standard deviation relative to "
                  "max(|value|, 5 % of the largest of its kind in the link). wls, ols: their MAP estimate (what the "
                  "log does not determine comes from the prior, with its data share); pcls: its prior. 0: no prior "
                  "(wls, ols: undetermined parameters held at 0; pcls: consistency alone)")
      ->capture_default_str();
  cmd->add_option("--range-width", opt.range_width,
                  "gd, ga, pf: each standard parameter searched within robot.json's value +- this x max(|value|, 5 % "
                  "of the largest of its kind in the link)")
      ->capture_default_str();
  cmd->add_option("--seed", opt.seed, "ga, pf: random seed (the result is deterministic for a seed)")
      ->capture_default_str();
  cmd->add_option("--evaluations", opt.search_evaluations,
                  "gd: cost evaluations at most (default 20000), ga: generations (1500), pf: evaluations per "
                  "particle (1500); 0: the default")
      ->capture_default_str();
  cmd->add_option("--cutoff", opt.cutoff_hz, "zero-phase Butterworth cut-off [Hz]")->capture_default_str();
  cmd->add_option("--filter-order", opt.filter_order, "Butterworth order (even)")->capture_default_str();
  cmd->add_option("--decimate", opt.decimate, "decimation factor (0: automatic, about 25 x cut-off)")
      ->capture_default_str();
  cmd->add_option("--folds", opt.folds, "folds of the blocked cross-validation")->capture_default_str();
  cmd->add_option("--block", opt.block_seconds, "cross-validation block length [s]")->capture_default_str();
  cmd->add_option("--validate-last", opt.validate_last, "validate on this final fraction instead (time split)");
  cmd->add_option("--mu", opt.rls_mu, "RLS forgetting factor mu (survey Eq. 23)")->capture_default_str();
  cmd->add_option("--p0", opt.p0, "KF/RLS initial covariance diagonal")->capture_default_str();
  cmd->add_option("--min-speed", opt.min_speed_fraction,
                  "fit only rows where |qd_j| >= this fraction of joint j's top speed (stiction)")
      ->capture_default_str();
  cmd->add_option("--validate-on", s->validate_on,
                  "also predict this other log (same --format) with the final fit and report its per-joint RMS, R^2 "
                  "and e_T_abs; repeat for several")
      ->take_all();
  cmd->add_flag("--sign-constraints", opt.sign_constraints,
                "wls, ols: Coulomb, viscous friction and rotor inertia held >= 0 (Lawson-Hanson), as a drive table "
                "must have them");
  cmd->add_flag("--strict", opt.strict,
                "refuse (exit 2) a log that does not determine every parameter of the model, instead of dropping "
                "those it does not determine with a note (docs/accuracy.md \"Real arms\")");
  cmd->add_flag("--friction-per-joint", opt.friction_per_joint,
                "friction and rotor inertia per joint, ignoring a coupling robot.json's transmission declares");
  cmd->add_option("--loaded-data", s->loaded,
                  "--torque-from current: a log of the same arm with a load of known mass on the last link; "
                  "identifies each motor's Kt from the pair (--data the unloaded log) before the fit, in place of "
                  "robot.json's (docs/robots.md); repeat to stack several")
      ->take_all();
  cmd->add_option("--load-mass", s->load_mass, "--loaded-data: the load's mass [kg]");
  cmd->add_option("--load-com", s->load_com,
                  "--loaded-data: the load's centre of mass x y z [m] in the last link's frame (robot.json's), if "
                  "known; else fitted")
      ->expected(3);
  add_report_options(cmd, s->out, "identify", "write the report as JSON");
  cmd->add_option("--params", s->params, "write the identified parameter table as JSON");
  cmd->add_flag("--compare-friction", s->compare_friction,
                "fit each friction model (survey Eq. 4-9) with the --model's other terms and compare their "
                "torque error on the fitted part and on the last --validate-last (default 0.3) of the log "
                "(survey Table 12)");
  cmd->callback([&run, s] { run = [s] { return run_identify(*s); }; });
}

}  // namespace dyncal::app
