#include "dyncal_host/common/trajectory_file.hpp"

#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

namespace mm = dyncal::modbus_map;

void trajectory_extremes(const ExcitationTrajectory& t, int grid, TrajectoryVec& qmin, TrajectoryVec& qmax,
                         TrajectoryVec& vmax, TrajectoryVec& amax) {
  qmin.setConstant(std::numeric_limits<double>::infinity());
  qmax = -qmin;
  vmax.setZero();
  amax.setZero();
  for (int k = 0; k < grid; ++k) {
    TrajectoryVec q, qd, qdd;
    t.evaluate(t.period() * k / grid, q, qd, qdd);
    qmin = qmin.cwiseMin(q);
    qmax = qmax.cwiseMax(q);
    vmax = vmax.cwiseMax(qd.cwiseAbs());
    amax = amax.cwiseMax(qdd.cwiseAbs());
  }
}

void limit_use(const RobotDescription& robot, const ExcitationTrajectory& t, JointFractions& position,
               JointFractions& velocity, JointFractions& acceleration) {
  TrajectoryVec qmin, qmax, vmax, amax;
  trajectory_extremes(t, 2000, qmin, qmax, vmax, amax);
  position.fill(0);
  velocity.fill(0);
  acceleration.fill(0);
  for (int j = 0; j < robot.num_joints; ++j) {
    const double centre = 0.5 * (robot.q_max[j] + robot.q_min[j]), half = 0.5 * (robot.q_max[j] - robot.q_min[j]);
    position[j] = std::max(std::fabs(qmax[j] - centre), std::fabs(qmin[j] - centre)) / half;
    velocity[j] = vmax[j] / robot.qd_max[j];
    acceleration[j] = amax[j] / robot.qdd_max[j];
  }
}

nlohmann::json trajectory_to_json(const RobotDescription& robot, const ExcitationTrajectory& t) {
  nlohmann::json j;
  j["robot"] = robot.name;
  j["f_f"] = t.f_f;
  j["harmonics"] = t.harmonics;
  for (int i = 0; i < robot.num_joints; ++i) {
    j["q0"].push_back(t.q0[i]);
    nlohmann::json a = nlohmann::json::array(), b = nlohmann::json::array();
    for (int l = 0; l < t.harmonics; ++l) {
      a.push_back(t.a(i, l));
      b.push_back(t.b(i, l));
    }
    j["a"].push_back(a);
    j["b"].push_back(b);
  }
  return j;
}

ExcitationTrajectory trajectory_from_json(const RobotDescription& robot, const nlohmann::json& j) {
  auto need = [&](const char* key) -> const nlohmann::json& {
    if (!j.is_object() || !j.contains(key)) throw InputError(std::string("trajectory file: missing '") + key + "'");
    return j[key];
  };
  auto number = [](const nlohmann::json& v, const std::string& what) {
    if (!v.is_number() || !std::isfinite(v.get<double>()))
      throw InputError("trajectory file: " + what + " is not a number");
    return v.get<double>();
  };
  if (need("robot").get<std::string>() != robot.name) {
    throw InputError("trajectory file is for robot '" + j["robot"].get<std::string>() + "', not '" + robot.name + "'");
  }
  ExcitationTrajectory t;
  t.f_f = number(need("f_f"), "f_f");
  if (!need("harmonics").is_number_integer()) throw InputError("trajectory file: harmonics is not an integer");
  t.harmonics = j["harmonics"].get<int>();
  if (!(t.f_f > 0) || t.harmonics < 1 || t.harmonics > mm::kMaxHarmonics) {
    throw InputError("trajectory file: f_f must be > 0 and harmonics 1..8");
  }
  const auto& q0 = need("q0");
  const auto& a = need("a");
  const auto& b = need("b");
  const size_t n = static_cast<size_t>(robot.num_joints);
  if (!q0.is_array() || q0.size() != n || !a.is_array() || a.size() != n || !b.is_array() || b.size() != n) {
    throw InputError("trajectory file: q0, a and b need one entry per joint (" + std::to_string(n) + ")");
  }
  for (size_t i = 0; i < n; ++i) {
    const std::string joint = " of joint " + std::to_string(i + 1);
    t.q0[static_cast<Eigen::Index>(i)] = number(q0[i], "q0" + joint);
    if (!a[i].is_array() || a[i].size() != static_cast<size_t>(t.harmonics) || !b[i].is_array() ||
        b[i].size() != static_cast<size_t>(t.harmonics)) {
      throw InputError("trajectory file: a and b" + joint + " need " + std::to_string(t.harmonics) + " coefficients");
    }
    for (int l = 0; l < t.harmonics; ++l) {
      t.a(static_cast<Eigen::Index>(i), l) = number(a[i][static_cast<size_t>(l)], "a" + joint);
      t.b(static_cast<Eigen::Index>(i), l) = number(b[i][static_cast<size_t>(l)], "b" + joint);
    }
  }
  JointFractions pos{}, vel{}, acc{};
  limit_use(robot, t, pos, vel, acc);
  for (int i = 0; i < robot.num_joints; ++i) {
    for (const auto& [use, what] : {std::pair{pos[i], "position range"}, std::pair{vel[i], "velocity limit"},
                                    std::pair{acc[i], "acceleration limit"}}) {
      if (use > 1.0) {
        throw InputError("trajectory file: joint " + std::to_string(i + 1) + " exceeds its " + what + " (" +
                         std::to_string(static_cast<int>(std::lround(100 * use))) + " % of it)");
      }
    }
  }
  return t;
}

}  // namespace dyncal::host
