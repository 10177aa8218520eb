#include "dyncal_host/common/robot_description.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {
namespace {

double number_field(const nlohmann::json& j, const char* key, double fallback, const std::string& where) {
  if (!j.contains(key)) return fallback;
  if (!j[key].is_number()) throw InputError(where + ": '" + key + "' must be a number");
  const double v = j[key].get<double>();
  if (!std::isfinite(v)) throw InputError(where + ": '" + key + "' is not finite");
  return v;
}

Eigen::VectorXd vector_field(const nlohmann::json& j, const char* key, int n, const std::string& where) {
  if (!j.contains(key) || !j[key].is_array()) throw InputError(where + ": missing array '" + key + "'");
  const auto& a = j[key];
  if (static_cast<int>(a.size()) != n) {
    throw InputError(where + ": '" + key + "' has " + std::to_string(a.size()) + " entries, expected " +
                     std::to_string(n));
  }
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = a[static_cast<size_t>(i)].get<double>();
  return v;
}

}  // namespace

std::string default_robots_dir() {
  if (const char* env = std::getenv("DYNCAL_ROBOTS")) return env;
  return DYNCAL_SOURCE_ROBOTS_DIR;
}

RobotDescription load_robot(const std::string& robots_dir, const std::string& name) {
  const std::string path = robots_dir + "/" + name + "/robot.json";
  std::ifstream in(path);
  if (!in) throw InputError("unknown robot '" + name + "' (no " + path + ")");
  nlohmann::json j;
  try {
    in >> j;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": invalid JSON: " + e.what());
  }
  RobotDescription r;
  r.name = name;
  r.directory = robots_dir + "/" + name;
  try {
    const auto& tr = j.at("transmission");
    r.gear_ratios = vector_field(tr, "gear_ratios", static_cast<int>(tr.at("gear_ratios").size()), path);
    r.num_joints = static_cast<int>(r.gear_ratios.size());
    const int n = r.num_joints;
    r.transmission = r.gear_ratios.asDiagonal();
    for (const auto& c : tr.at("coupling")) {
      const int motor = c.at("motor").get<int>();
      const int joint = c.at("joint").get<int>();
      if (motor < 1 || motor > n || joint < 1 || joint > n) throw InputError(path + ": coupling joint out of range");
      r.transmission(motor - 1, joint - 1) = c.at("ratio").get<double>();
    }
    r.joint_offsets = vector_field(tr, "joint_offsets", n, path);
    const auto& lim = j.at("limits");
    r.q_min = vector_field(lim, "q_min", n, path);
    r.q_max = vector_field(lim, "q_max", n, path);
    r.qd_max = vector_field(lim, "qd_max", n, path);
    r.qdd_max = vector_field(lim, "qdd_max", n, path);
    r.tau_max = vector_field(lim, "tau_max", n, path);
    r.friction.assign(static_cast<size_t>(n), NominalFriction{});
    if (j.contains("friction")) {
      const auto& fr = j["friction"];
      if (!fr.is_array() || static_cast<int>(fr.size()) != n)
        throw InputError(path + ": 'friction' must list one entry per joint (" + std::to_string(n) + ")");
      for (int k = 0; k < n; ++k) {
        const auto& fj = fr[static_cast<size_t>(k)];
        const std::string where = path + ": friction of joint " + std::to_string(k + 1);
        NominalFriction& f = r.friction[static_cast<size_t>(k)];
        f.Fc = number_field(fj, "Fc", 0, where);
        f.beta = number_field(fj, "beta", 0, where);
        f.Fs = number_field(fj, "Fs", f.Fc, where);
        f.qds = number_field(fj, "qds", 0.1, where);
      }
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": " + e.what());
  }
  return r;
}

}  // namespace dyncal::host
