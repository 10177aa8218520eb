#include "dyncal_host/model/compiled_robot.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/number_text.hpp"
#include "dyncal_host/model/inertial_parameters.hpp"

namespace dyncal::host {
namespace {

// Function-local static: the robots' static initialisers may run before any other of this file.
std::map<std::string, CompiledRobot>& registry() {
  static std::map<std::string, CompiledRobot> robots;
  return robots;
}

}  // namespace

bool register_robot(const CompiledRobot& robot) {
  CompiledRobot& entry = registry()[robot.name];
  entry.name = robot.name;
  if (robot.num_joints) {
    entry.robot_id = robot.robot_id;
    entry.num_joints = robot.num_joints;
    entry.num_standard = robot.num_standard;
    entry.num_base = robot.num_base;
    entry.nominal_standard = robot.nominal_standard;
    entry.prismatic = robot.prismatic;
  }
  for (int i = 0; i < kBuiltTermSets; ++i) {
    const auto k = static_cast<size_t>(i);
    if (robot.models[k].regressor) entry.models[k] = robot.models[k];
  }
  if (robot.excitation_regressor) entry.excitation_regressor = robot.excitation_regressor;
  if (robot.inverse_dynamics) entry.inverse_dynamics = robot.inverse_dynamics;
  if (robot.standard_to_base) entry.standard_to_base = robot.standard_to_base;
  if (robot.base_regressor) entry.base_regressor = robot.base_regressor;
  if (robot.momentum_residual) entry.momentum_residual = robot.momentum_residual;
  if (robot.direct_residual) entry.direct_residual = robot.direct_residual;
  return true;
}

std::vector<std::string> compiled_robot_names() {
  std::vector<std::string> names;
  for (const auto& [name, robot] : registry()) names.push_back(name);
  return names;
}

const CompiledRobot& compiled_robot(const std::string& name) {
  const auto it = registry().find(name);
  if (it == registry().end() || it->second.num_joints == 0) {
    std::string known;
    for (const std::string& n : compiled_robot_names()) known += (known.empty() ? "" : ", ") + n;
    throw InputError("robot '" + name + "' has no compiled model in this build (compiled: " + known + "); add robots/" +
                     name + "/ (docs/robots.md) and build again");
  }
  return it->second;
}

const CompiledRobot& compiled_robot_for(const RobotDescription& robot) {
  const CompiledRobot& c = compiled_robot(robot.name);
  if (robot.num_joints != c.num_joints) {
    throw InputError(robot.directory + "/robot.json lists " + std::to_string(robot.num_joints) +
                     " joints, its compiled model has " + std::to_string(c.num_joints) + ": build again");
  }
  for (int j = 0; j < c.num_joints && static_cast<size_t>(j) < robot.prismatic.size(); ++j) {
    if (robot.prismatic[static_cast<size_t>(j)] != static_cast<bool>(c.prismatic[static_cast<size_t>(j)]))
      throw InputError(robot.directory + "/robot.json: joint " + std::to_string(j + 1) + " is " +
                       (robot.prismatic[static_cast<size_t>(j)] ? "prismatic" : "revolute") +
                       ", in its compiled model " + (c.prismatic[static_cast<size_t>(j)] ? "prismatic" : "revolute") +
                       ": build again (scripts/build) after robot check, or undo the edit");
  }
  // An MDH robot's inertials are compiled from robot.json: an edit since the build is named, not
  // silently replaced by the compiled values (a URDF robot's are checked against KDL by robot check).
  static const char* kFields[10] = {"mass",       "com[1]",     "com[2]",     "com[3]",     "inertia[1]",
                                    "inertia[2]", "inertia[3]", "inertia[4]", "inertia[5]", "inertia[6]"};
  for (size_t k = 0; k < robot.links.size() && 10 * (k + 1) <= c.nominal_standard.size(); ++k) {
    const LinkInertialSpec& l = robot.links[k];
    const std::array<double, 10> stated = {l.mass,       l.com[0],     l.com[1],     l.com[2],     l.inertia[0],
                                           l.inertia[1], l.inertia[2], l.inertia[3], l.inertia[4], l.inertia[5]};
    std::array<double, 10> phi{};
    standard_from_physical(stated, phi.data());
    const std::array<double, 10> compiled = physical_parameters(c.nominal_standard.data() + 10 * k);
    double worst = 0;
    for (size_t i = 0; i < 10; ++i)
      worst = std::max(worst, std::abs(phi[i] - c.nominal_standard[10 * k + i]) /
                                  std::max(1.0, std::abs(c.nominal_standard[10 * k + i])));
    if (!(worst <= 1e-9)) {
      size_t field = 0;
      for (size_t i = 1; i < 10; ++i)
        if (std::abs(stated[i] - compiled[i]) > std::abs(stated[field] - compiled[field])) field = i;
      throw InputError(robot.directory + "/robot.json: links[" + std::to_string(k + 1) + "]." + kFields[field] + " " +
                       number_text(stated[field], 12) + " differs from the compiled model's " +
                       number_text(compiled[field], 12) +
                       " (this build compiled an earlier robot.json): build again "
                       "(scripts/build) after robot check, or undo the edit");
    }
  }
  return c;
}

RobotDescription load_checked_robot(const std::string& robots_dir, const std::string& name) {
  RobotDescription r = load_robot(robots_dir, name);
  compiled_robot_for(r);
  derive_tau_max(r);
  return r;
}

void derive_tau_max(RobotDescription& robot) {
  if (robot.tau_max.size() == robot.num_joints) return;
  const CompiledRobot& c = compiled_robot_for(robot);
  const int n = robot.num_joints;
  const Eigen::VectorXd phi = Eigen::Map<const Eigen::VectorXd>(c.nominal_standard.data(), c.num_standard);
  std::mt19937_64 rng(kDerivedTauMaxSeed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::VectorXd q(n), qd(n), qdd(n), peak = Eigen::VectorXd::Zero(n);
  for (int s = 0; s < kDerivedTauMaxSamples; ++s) {
    for (int j = 0; j < n; ++j) {
      q[j] = robot.q_min[j] + u(rng) * (robot.q_max[j] - robot.q_min[j]);
      qd[j] = (2 * u(rng) - 1) * robot.qd_max[j];
      qdd[j] = (2 * u(rng) - 1) * robot.qdd_max[j];
    }
    peak = peak.cwiseMax(c.inverse_dynamics(q, qd, qdd, phi).cwiseAbs());
  }
  for (int j = 0; j < n; ++j) {
    if (!(peak[j] > 0))
      throw InputError(robot.directory + "/robot.json: limits.tau_max missing and joint " + std::to_string(j + 1) +
                       " carries no torque in the nominal model: state limits.tau_max");
  }
  robot.tau_max = peak;
  robot.tau_max_derived = true;
}

const TermSetModel& term_set_model(const CompiledRobot& robot, unsigned terms) {
  const TermSetModel& m = robot.models[static_cast<size_t>(built_term_set_index(terms))];
  if (!m.regressor) throw InputError("robot '" + robot.name + "' has no identification model compiled: build again");
  return m;
}

Eigen::MatrixXd base_map(const CompiledRobot& robot) {
  Eigen::MatrixXd K(robot.num_base, robot.num_standard);
  for (int i = 0; i < robot.num_standard; ++i)
    K.col(i) = robot.standard_to_base(Eigen::VectorXd::Unit(robot.num_standard, i));
  return K;
}

}  // namespace dyncal::host
