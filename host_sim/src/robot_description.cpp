#include "dyncal_host/robot_description.hpp"

#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>

#include "dyncal_host/input_error.hpp"

namespace dyncal::host {
namespace {

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
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": " + e.what());
  }
  return r;
}

}  // namespace dyncal::host
