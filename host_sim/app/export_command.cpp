// dyncal export urdf: the identified model written into the URDF the robot was imported from
// (docs/export.md). The URDF work is codegen/import_urdf.py's (urdf_export.py); this file gives it
// the identified inertials and terms and dyncal's own rigid-body torques at random states, which
// KDL's inverse dynamics of the written file must reproduce before it is written. dyncal export
// mjcf: the identified model as MJCF (codegen's mjcf_export.py), written only when MuJoCo's inverse
// dynamics of it reproduces dyncal's model.
#include <unistd.h>

#include <Eigen/Core>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <random>
#include <regex>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/model_effects.hpp"
#include "dyncal_host/common/output_file.hpp"
#include "dyncal_host/common/temporary_folder.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/model/inertial_parameters.hpp"
#include "mujoco_model.hpp"

namespace dyncal::app {
namespace {

using host::InputError;

/// Random states of the KDL and MuJoCo checks: q within the joint range, |qd| <= qd_max, |qdd| <= qdd_max.
constexpr int kCheckStates = 64;
/// The MuJoCo check's tolerance, relative to max(1, |tau|) (as the KDL check's, kdl_check.py).
constexpr double kCheckTolerance = 1e-9;

/// `v` as printf's %.3g.
std::string number_text(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", v);
  return text;
}

struct ExportSettings {
  std::string params, out, robots_dir;
  bool force = false;  ///< write links whose mass is not told from 0, marked in the file
};

/// A pcls parameter file's model: the set, its robot, the standard parameters its links give, and
/// the links as the tools' JSON. Throws InputError: no links (not pcls), links that do not give the
/// file's own base parameters (Gautier's map, to 1e-6 of the largest).
struct IdentifiedModel {
  host::ParameterSet params;
  host::RobotDescription robot;
  const host::CompiledRobot* compiled = nullptr;
  Eigen::VectorXd phi;  ///< standard parameters (10 per link)
  nlohmann::json links = nlohmann::json::array();
};

IdentifiedModel identified_model(const ExportSettings& s, const char* format) {
  IdentifiedModel m;
  m.params = host::read_parameter_file(s.params);
  const host::ParameterSet& p = m.params;
  if (p.links.empty())
    throw InputError(s.params + ": export " + format +
                     " needs each link's inertials and the file has none: the base parameters do not "
                     "determine them; identify with --method pcls (physically consistent, Wensing et al.) writes them");
  m.robot = host::load_checked_robot(s.robots_dir, p.robot);
  m.compiled = &host::compiled_robot(p.robot);
  const host::CompiledRobot& c = *m.compiled;
  m.phi = Eigen::VectorXd::Zero(c.num_standard);
  std::string undetermined;
  for (const host::LinkInertial& l : p.links) {
    const std::array<double, 10> physical = {l.mass,       l.com[0],     l.com[1],     l.com[2],     l.inertia[0],
                                             l.inertia[1], l.inertia[2], l.inertia[3], l.inertia[4], l.inertia[5]};
    host::standard_from_physical(physical, m.phi.data() + 10 * (l.link - 1));
    nlohmann::json link = {{"mass", l.mass}, {"com", l.com}, {"inertia_about_com", l.inertia}};
    if (std::isfinite(l.mass_std)) link["mass_std"] = l.mass_std;  // none: neither data nor prior fix it
    if (!l.mass_basis.empty()) link["mass_basis"] = l.mass_basis;
    // A mass its own 95 % interval does not tell from 0, fitted without a prior, rests on nothing.
    if (l.mass_basis == "neither") {
      char v[200];
      if (std::isfinite(l.mass_std))
        std::snprintf(v, sizeof v, "link %d (mass %.4g +- %.2g kg std)", l.link, l.mass, l.mass_std);
      else
        std::snprintf(v, sizeof v, "link %d (mass %.4g kg, no interval)", l.link, l.mass);
      undetermined += (undetermined.empty() ? "" : ", ") + std::string(v);
      link["not_determined"] = true;
    }
    m.links.push_back(link);
  }
  if (!undetermined.empty() && !s.force)
    throw InputError(s.params + ": " + undetermined +
                     ": its 95 % interval holds 0 and the fit had no prior: neither the log nor a prior fixes it "
                     "(identify --method pcls with its prior, --prior-std > 0, or a log that moves it); nothing "
                     "exported" +
                     std::string(std::string(format) == "urdf" ? " (--force writes it, marked in the file)" : ""));
  // The links must be the file's rigid body: their base parameters are the file's (Gautier's map).
  const Eigen::VectorXd base = c.standard_to_base(m.phi);
  const Eigen::VectorXd file_base = p.values.head(c.num_base);
  const double scale = std::max(1e-12, file_base.cwiseAbs().maxCoeff());
  if ((base - file_base).cwiseAbs().maxCoeff() > 1e-6 * scale)
    throw InputError(s.params +
                     ": its links' inertials do not give its base parameters (the file was edited?): "
                     "nothing exported");
  return m;
}

/// `count` seeded random states (q within the joint range, |qd| <= qd_max, |qdd| <= qdd_max).
struct RandomState {
  Eigen::VectorXd q, qd, qdd;
};
std::vector<RandomState> random_states(const host::RobotDescription& robot, int count) {
  std::mt19937_64 rng(44);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<RandomState> states;
  const int n = robot.num_joints;
  for (int k = 0; k < count; ++k) {
    RandomState x{Eigen::VectorXd(n), Eigen::VectorXd(n), Eigen::VectorXd(n)};
    for (int j = 0; j < n; ++j) {
      x.q[j] = robot.q_min[j] + 0.5 * (u(rng) + 1.0) * (robot.q_max[j] - robot.q_min[j]);
      x.qd[j] = u(rng) * robot.qd_max[j];
      x.qdd[j] = u(rng) * robot.qdd_max[j];
    }
    states.push_back(x);
  }
  return states;
}

nlohmann::json provenance(const ExportSettings& s, const host::ParameterSet& p) {
  return {{"params", std::filesystem::path(s.params).filename().string()}, {"robot", p.robot}, {"model", p.model}};
}

int run_export_urdf(const ExportSettings& s) {
  host::check_output_path(s.out, "URDF");  // before the work: a FIFO, a device, a folder, a missing folder
  const IdentifiedModel m = identified_model(s, "urdf");
  const host::ParameterSet& p = m.params;
  const host::CompiledRobot& c = *m.compiled;
  nlohmann::json terms = nlohmann::json::array();
  for (Eigen::Index i = c.num_base; i < p.values.size(); ++i)
    terms.push_back({{"name", p.names[static_cast<size_t>(i)]}, {"value", p.values[i]}});
  nlohmann::json samples = nlohmann::json::array();
  for (const RandomState& x : random_states(m.robot, kCheckStates)) {
    const Eigen::VectorXd tau = c.inverse_dynamics(x.q, x.qd, x.qdd, m.phi);
    auto list = [](const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); };
    samples.push_back({{"q", list(x.q)}, {"qd", list(x.qd)}, {"qdd", list(x.qdd)}, {"tau", list(tau)}});
  }
  const nlohmann::json input = {
      {"links", m.links}, {"terms", terms}, {"samples", samples}, {"provenance", provenance(s, p)}};
  // The tool writes and checks the URDF in a folder of our own; the user's --out is then written by
  // the host's one writer (output_file.hpp): all or nothing, a regular file or a new name only.
  const host::TemporaryFolder folder("dyncal-export");
  const std::string input_file = folder.path() + "/input.json", urdf_name = p.robot + ".urdf";
  write_json_file(input_file, input);
  const int rc = run_urdf_tool({"export", p.robot, "--robots-dir", s.robots_dir, "--input", input_file, "--out",
                                folder.path() + "/" + urdf_name});
  if (rc != 0) return rc;
  const std::string text = folder.read(urdf_name);
  host::write_output_file(s.out, text, "URDF");
  std::cout << p.robot << ": wrote " << s.out << "\n";
  return 0;
}

/// Per joint what a MuJoCo joint holds (armature = Ia, damping = Fv, frictionloss = Fc), and the
/// terms it cannot hold with the reason.
struct MjcfTerms {
  Eigen::VectorXd armature, damping, frictionloss;
  nlohmann::json not_held = nlohmann::json::array();
};

/// What term column `i` of `model` is, read off the regressor itself at `states`: 0 armature, 1
/// damping, 2 Coulomb friction of joint *joint (its column e_j qdd_j, e_j qd_j or e_j sign(qd_j)), or
/// -1: anything else (an offset, a term acting through a coupled transmission on several joints).
int joint_term_kind(const host::TermSetModel& model, Eigen::Index i, const std::vector<RandomState>& states,
                    int* joint) {
  const int n = model.num_joints;
  Eigen::MatrixXd K(n, model.num_params);
  for (int kind = 0; kind < 3; ++kind)
    for (int j = 0; j < n; ++j) {
      bool all = true;
      for (const RandomState& x : states) {
        model.regressor(x.q.data(), x.qd.data(), x.qdd.data(), K.data());
        Eigen::VectorXd want = Eigen::VectorXd::Zero(n);
        want[j] = kind == 0 ? x.qdd[j] : kind == 1 ? x.qd[j] : (x.qd[j] > 0 ? 1.0 : -1.0);
        all = all && (K.col(i) - want).cwiseAbs().maxCoeff() <= 1e-12 * std::max(1.0, std::abs(want[j]));
      }
      if (all) {
        *joint = j;
        return kind;
      }
    }
  return -1;
}

MjcfTerms mjcf_terms(const host::ParameterSet& p, const host::CompiledRobot& c, const host::RobotDescription& robot) {
  const int n = c.num_joints;
  MjcfTerms t{Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n)};
  const host::TermSetModel& model = host::term_set_model(c, p.terms);
  // Three states and their mirror images (qd, qdd negated): an offset's column is then no sign(qd_j).
  std::vector<RandomState> states = random_states(robot, 3);
  for (int k = 0; k < 3; ++k) states.push_back({states[k].q, -states[k].qd, -states[k].qdd});
  // The regressor's term columns are per motor; the pipeline maps them to the joints through the
  // motor-velocity map T (robot.json's transmission, coupled_motor items): tau_joint = T^T tau_motor.
  const Eigen::MatrixXd T = host::motor_velocity_map(robot, p.friction_per_motor, p.motors);
  for (Eigen::Index i = c.num_base; i < p.values.size(); ++i) {
    const std::string& name = p.names[static_cast<size_t>(i)];
    const double v = p.values[i];
    int j = -1;
    const int kind = i < model.num_params ? joint_term_kind(model, i, states, &j) : -1;
    std::string why;
    if (kind < 0)
      why = name.rfind("offset", 0) == 0 ? "a torque offset: MuJoCo joints have none"
                                         : "it is not one joint's armature, damping or dry friction (a coupled "
                                           "transmission, an effect): no MuJoCo joint attribute holds it";
    else if ((T.row(j) - Eigen::RowVectorXd::Unit(n, j)).cwiseAbs().maxCoeff() > 0)
      why = "acts through the coupled transmission of motor " + std::to_string(j + 1) +
            " on several joints: a MuJoCo joint's armature, damping and frictionloss act on that joint alone";
    else if (v < 0)
      why = "negative: no joint has it physically (MuJoCo needs it >= 0)";
    if (!why.empty()) {
      t.not_held.push_back({{"name", name}, {"value", v}, {"why", why}});
      continue;
    }
    (kind == 0 ? t.armature : kind == 1 ? t.damping : t.frictionloss)[j] = v;
  }
  return t;
}

int run_export_mjcf(const ExportSettings& s) {
  host::check_output_path(s.out, "MJCF");
  const IdentifiedModel m = identified_model(s, "mjcf");
  const host::ParameterSet& p = m.params;
  const host::CompiledRobot& c = *m.compiled;
  const int n = c.num_joints;
  const MjcfTerms terms = mjcf_terms(p, c, m.robot);
  nlohmann::json joints = nlohmann::json::array();
  for (int j = 0; j < n; ++j)
    joints.push_back(
        {{"armature", terms.armature[j]}, {"damping", terms.damping[j]}, {"frictionloss", terms.frictionloss[j]}});
  const nlohmann::json input = {
      {"links", m.links}, {"joints", joints}, {"not_held", terms.not_held}, {"provenance", provenance(s, p)}};
  const host::TemporaryFolder folder("dyncal-export");
  const std::string input_file = folder.path() + "/input.json", mjcf_name = p.robot + ".xml";
  write_json_file(input_file, input);
  const int rc = run_urdf_tool(
      {"mjcf", p.robot, "--robots-dir", s.robots_dir, "--input", input_file, "--out", folder.path() + "/" + mjcf_name});
  if (rc != 0) return rc;
  // MuJoCo's own inverse dynamics of the file must be dyncal's model: the rigid body with the
  // identified inertials plus the terms the joints hold, Ia qdd_j and Fv qd_j (mjcf_terms took only
  // terms whose regressor column is exactly that; dry friction is a constraint in MuJoCo, off in the
  // check: its value is written as identified).
  MujocoModel mujoco(folder.path() + "/" + mjcf_name);
  if (mujoco.dofs() != n)
    throw InputError("internal: MuJoCo reads " + std::to_string(mujoco.dofs()) +
                     " joints in the written MJCF, the robot has " + std::to_string(n) + "; nothing written");
  double worst = 0;
  for (const RandomState& x : random_states(m.robot, kCheckStates)) {
    const Eigen::VectorXd want = c.inverse_dynamics(x.q, x.qd, x.qdd, m.phi) + terms.armature.cwiseProduct(x.qdd) +
                                 terms.damping.cwiseProduct(x.qd);
    const Eigen::VectorXd got = mujoco.inverse_dynamics(x.q, x.qd, x.qdd);
    for (int j = 0; j < n; ++j) worst = std::max(worst, std::abs(got[j] - want[j]) / std::max(1.0, std::abs(want[j])));
  }
  if (!(worst <= kCheckTolerance))
    throw InputError("internal: MuJoCo's inverse dynamics of the written MJCF differs from dyncal's model by " +
                     number_text(worst) + " (relative); nothing written");
  host::write_output_file(s.out, folder.read(mjcf_name), "MJCF");
  std::cout << p.robot << ": wrote " << s.out << "; MuJoCo's inverse dynamics of it matches dyncal's model to "
            << number_text(worst) << " (relative, " << kCheckStates << " random states)\n";
  if (!terms.not_held.empty()) {
    std::cout << "not held by MJCF (kept as <custom><numeric name=\"dyncal_NAME\">):";
    for (const auto& t : terms.not_held)
      std::cout << "\n  " << t["name"].get<std::string>() << " " << number_text(t["value"].get<double>()) << ": "
                << t["why"].get<std::string>();
    std::cout << "\n";
  }
  return 0;
}

}  // namespace

void add_export_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<ExportSettings>();
  s->robots_dir = host::default_robots_dir();
  auto* cmd = app.add_subcommand("export", "write the identified model out for other tools");
  cmd->require_subcommand(1);
  auto* urdf = cmd->add_subcommand(
      "urdf",
      "the URDF the robot was imported from with each link's inertial replaced by the identified one (--method "
      "pcls parameter file), friction in <dynamics>, the other terms in a <dyncal> element; written only when "
      "orocos-kdl's inverse dynamics of it reproduces dyncal's model (docs/export.md)");
  urdf->add_option("--params", s->params, "parameter file of identify --method pcls --params")->required();
  urdf->add_option("--out", s->out, "the URDF to write")->required();
  urdf->add_option("--robots-dir", s->robots_dir, "directory holding the robot descriptions");
  urdf->add_flag("--force", s->force,
                 "write a link whose mass its 95 % interval does not tell from 0 (refused otherwise), marked in the "
                 "file");
  urdf->callback([&run, s] { run = [s] { return run_export_urdf(*s); }; });
  auto* mjcf = cmd->add_subcommand(
      "mjcf",
      "the identified model (--method pcls parameter file) as an MJCF file for MuJoCo: each link's inertial, joint "
      "armature = Ia, damping = Fv, frictionloss = Fc, the terms MJCF cannot hold listed; written only when "
      "MuJoCo's inverse dynamics of it reproduces dyncal's model (docs/export.md)");
  mjcf->add_option("--params", s->params, "parameter file of identify --method pcls --params")->required();
  mjcf->add_option("--out", s->out, "the MJCF file to write")->required();
  mjcf->add_option("--robots-dir", s->robots_dir, "directory holding the robot descriptions");
  mjcf->callback([&run, s] { run = [s] { return run_export_mjcf(*s); }; });
}

}  // namespace dyncal::app
