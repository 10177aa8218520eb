#include "dyncal_host/common/robot_description.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/json_file.hpp"
#include "dyncal_host/common/source_tree.hpp"

namespace dyncal::host {
namespace {

using nlohmann::json;

/// Field errors name the file and the field as docs/robots.md does ("limits.q_max[2]"), on one line.
struct Reader {
  std::string path;

  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw InputError(path + ": " + field + ": " + what);
  }

  double number(const json& v, const std::string& field, bool positive = false) const {
    if (!v.is_number()) fail(field, "expected a number, got " + v.dump());
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(field, "is not finite");
    if (positive && x <= 0) fail(field, "must be > 0, got " + v.dump());
    return x;
  }

  const json* object(const json& parent, const char* key, const std::string& field, bool required) const {
    if (!parent.contains(key)) {
      if (required) fail(field, "missing");
      return nullptr;
    }
    if (!parent[key].is_object()) fail(field, "expected an object");
    return &parent[key];
  }

  /// An array of n finite numbers (n < 0: any length >= 1), or an empty vector when optional and absent.
  Eigen::VectorXd vector(const json& parent, const char* key, int n, const std::string& field, bool required,
                         bool positive = false) const {
    if (!parent.contains(key)) {
      if (required) fail(field, "missing");
      return {};
    }
    const json& a = parent[key];
    if (!a.is_array() || a.empty()) fail(field, "expected a list of numbers, one per joint");
    if (n >= 0 && static_cast<int>(a.size()) != n)
      fail(field, std::to_string(a.size()) + " entries, expected " + std::to_string(n) + " (one per joint)");
    Eigen::VectorXd v(static_cast<Eigen::Index>(a.size()));
    for (size_t i = 0; i < a.size(); ++i)
      v[static_cast<Eigen::Index>(i)] = number(a[i], field + "[" + std::to_string(i + 1) + "]", positive);
    return v;
  }

  int joint_index(const json& c, const char* key, int n, const std::string& field) const {
    if (!c.contains(key) || !c[key].is_number_integer())
      fail(field + "." + key, "expected a joint number 1.." + std::to_string(n));
    const int k = c[key].get<int>();
    if (k < 1 || k > n) fail(field + "." + key, std::to_string(k) + " is not a joint 1.." + std::to_string(n));
    return k - 1;
  }
};

json read_json(const std::string& name, const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError("unknown robot '" + name + "' (no " + path + ")");
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path + ": not a regular file");
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot be read");
  try {
    json j;
    in >> j;
    return j;
  } catch (const json::exception& e) {
    throw InputError(path + ": invalid JSON: " + printable_message(e.what()));
  }
}

void read_limits(const Reader& rd, const json& j, RobotDescription& r) {
  const json& lim = *rd.object(j, "limits", "limits", true);
  r.q_min = rd.vector(lim, "q_min", -1, "limits.q_min", true);
  r.num_joints = static_cast<int>(r.q_min.size());
  const int n = r.num_joints;
  if (n > kMaxRobotDescriptionJoints)
    rd.fail("limits.q_min",
            std::to_string(n) + " joints; dyncal takes 1 to " + std::to_string(kMaxRobotDescriptionJoints));
  r.q_max = rd.vector(lim, "q_max", n, "limits.q_max", true);
  for (int i = 0; i < n; ++i) {
    if (!(r.q_max[i] > r.q_min[i]))
      rd.fail("limits.q_max[" + std::to_string(i + 1) + "]",
              std::to_string(r.q_max[i]) + " is not above q_min " + std::to_string(r.q_min[i]));
  }
  r.qd_max = rd.vector(lim, "qd_max", n, "limits.qd_max", true, true);
  r.qdd_max = rd.vector(lim, "qdd_max", n, "limits.qdd_max", false, true);
  if (r.qdd_max.size() == 0) r.qdd_max = kDefaultQddPerQd * r.qd_max;
  r.tau_max = rd.vector(lim, "tau_max", n, "limits.tau_max", false, true);
}

/// kinematics and, for an MDH robot, its rows and links: the fields' types and counts, finite
/// values, a mass >= 0 and no inertia without mass (codegen/dyncal_codegen/schema.py's rules; the
/// values themselves are then compared with the compiled model, compiled_robot_for).
void read_kinematics(const Reader& rd, const json& j, RobotDescription& r) {
  const json& kin = *rd.object(j, "kinematics", "kinematics", true);
  if (!kin.contains("format") || !kin["format"].is_string() || (kin["format"] != "mdh" && kin["format"] != "urdf"))
    rd.fail("kinematics.format",
            "expected \"mdh\" or \"urdf\", got " + (kin.contains("format") ? kin["format"].dump() : "nothing"));
  r.kinematics_format = kin["format"].get<std::string>();
  const int n = r.num_joints;
  r.prismatic.assign(static_cast<size_t>(n), false);
  if (j.contains("joint_types")) {
    const json& types = j["joint_types"];
    if (!types.is_array() || static_cast<int>(types.size()) != n)
      rd.fail("joint_types", "expected a list of " + std::to_string(n) + " joint types (one per joint)");
    for (int k = 0; k < n; ++k) {
      const json& t = types[static_cast<size_t>(k)];
      if (!t.is_string() || (t != "revolute" && t != "prismatic"))
        rd.fail("joint_types[" + std::to_string(k + 1) + "]",
                "expected \"revolute\" or \"prismatic\", got " + t.dump());
      r.prismatic[static_cast<size_t>(k)] = t == "prismatic";
    }
  }
  if (r.kinematics_format == "urdf") {
    std::error_code ec;
    if (!kin.contains("file") || !kin["file"].is_string() ||
        !std::filesystem::is_regular_file(r.directory + "/" + kin["file"].get<std::string>(), ec))
      rd.fail("kinematics.file", "expected the name of a URDF file in " + r.directory);
    return;
  }
  if (!kin.contains("joints") || !kin["joints"].is_array() || static_cast<int>(kin["joints"].size()) != n)
    rd.fail("kinematics.joints",
            "expected a list of " + std::to_string(n) + " {alpha, a, d, theta} rows (one per joint)");
  for (int k = 0; k < n; ++k) {
    const json& row = kin["joints"][static_cast<size_t>(k)];
    const std::string field = "kinematics.joints[" + std::to_string(k + 1) + "]";
    if (!row.is_object()) rd.fail(field, "expected an object {alpha, a, d, theta}");
    for (const char* key : {"alpha", "a", "d", "theta"}) {
      if (!row.contains(key)) rd.fail(field + "." + key, "missing");
      rd.number(row[key], field + "." + key);
    }
    bool sigma = false;
    if (row.contains("sigma")) {
      const json& s = row["sigma"];
      if (!s.is_number_integer() || (s != 0 && s != 1))
        rd.fail(field + ".sigma", "expected 0 (revolute) or 1 (prismatic), got " + s.dump());
      sigma = s == 1;
    }
    if (j.contains("joint_types") && sigma != r.prismatic[static_cast<size_t>(k)])
      rd.fail("joint_types[" + std::to_string(k + 1) + "]", "differs from " + field + ".sigma");
    r.prismatic[static_cast<size_t>(k)] = sigma;
  }
  if (!j.contains("links") || !j["links"].is_array() || static_cast<int>(j["links"].size()) != n)
    rd.fail("links",
            "expected one {mass, com, inertia} entry per joint (" + std::to_string(n) + ") for an mdh description");
  for (int k = 0; k < n; ++k) {
    const json& l = j["links"][static_cast<size_t>(k)];
    const std::string field = "links[" + std::to_string(k + 1) + "]";
    if (!l.is_object()) rd.fail(field, "expected an object {mass, com, inertia}");
    LinkInertialSpec spec;
    if (!l.contains("mass")) rd.fail(field + ".mass", "missing");
    spec.mass = rd.number(l["mass"], field + ".mass");
    if (spec.mass < 0) rd.fail(field + ".mass", "must be >= 0 kg, got " + l["mass"].dump());
    const Eigen::VectorXd com = rd.vector(l, "com", 3, field + ".com", true);
    const Eigen::VectorXd inertia = rd.vector(l, "inertia", 6, field + ".inertia", true);
    for (int i = 0; i < 3; ++i) spec.com[static_cast<size_t>(i)] = com[i];
    for (int i = 0; i < 6; ++i) spec.inertia[static_cast<size_t>(i)] = inertia[i];
    if (spec.mass == 0 && inertia.cwiseAbs().maxCoeff() > 0) rd.fail(field + ".inertia", "an inertia without mass");
    r.links.push_back(spec);
  }
}

void read_transmission(const Reader& rd, const json& j, RobotDescription& r) {
  const int n = r.num_joints;
  r.gear_ratios = Eigen::VectorXd::Ones(n);
  r.joint_offsets = Eigen::VectorXd::Zero(n);
  const json* tr = rd.object(j, "transmission", "transmission", false);
  if (tr) {
    // Optional (docs/robots.md: default 1): a current-logging arm may give only its torque constants.
    const Eigen::VectorXd gear = rd.vector(*tr, "gear_ratios", n, "transmission.gear_ratios", false);
    if (gear.size() > 0) r.gear_ratios = gear;
    for (int i = 0; i < n; ++i)
      if (r.gear_ratios[i] == 0) rd.fail("transmission.gear_ratios[" + std::to_string(i + 1) + "]", "is 0");
    const Eigen::VectorXd off = rd.vector(*tr, "joint_offsets", n, "transmission.joint_offsets", false);
    if (off.size() > 0) r.joint_offsets = off;
    r.torque_constants = rd.vector(*tr, "torque_constants", n, "transmission.torque_constants", false);
    for (Eigen::Index i = 0; i < r.torque_constants.size(); ++i)
      if (r.torque_constants[i] == 0) rd.fail("transmission.torque_constants[" + std::to_string(i + 1) + "]", "is 0");
  }
  r.transmission = r.gear_ratios.asDiagonal();
  if (!tr || !tr->contains("coupling")) return;
  const json& cs = (*tr)["coupling"];
  if (!cs.is_array()) rd.fail("transmission.coupling", "expected a list of {motor, joint, ratio}");
  for (size_t k = 0; k < cs.size(); ++k) {
    const std::string field = "transmission.coupling[" + std::to_string(k + 1) + "]";
    const json& c = cs[k];
    if (!c.is_object()) rd.fail(field, "expected an object {motor, joint, ratio}");
    const int motor = rd.joint_index(c, "motor", n, field), joint = rd.joint_index(c, "joint", n, field);
    if (motor == joint) rd.fail(field, "motor and joint are the same (its ratio is gear_ratios)");
    if (!c.contains("ratio")) rd.fail(field + ".ratio", "missing");
    r.transmission(motor, joint) = rd.number(c["ratio"], field + ".ratio");
  }
}

void read_friction(const Reader& rd, const json& j, RobotDescription& r) {
  const int n = r.num_joints;
  r.friction.assign(static_cast<size_t>(n), NominalFriction{});
  if (!j.contains("friction")) return;
  const json& fr = j["friction"];
  if (!fr.is_array() || static_cast<int>(fr.size()) != n)
    rd.fail("friction", "expected one entry per joint (" + std::to_string(n) + ")");
  for (int k = 0; k < n; ++k) {
    const json& fj = fr[static_cast<size_t>(k)];
    const std::string field = "friction[" + std::to_string(k + 1) + "]";
    if (!fj.is_object()) rd.fail(field, "expected an object {Fc, beta, Fs, qds}");
    NominalFriction& f = r.friction[static_cast<size_t>(k)];
    if (fj.contains("Fc")) f.Fc = rd.number(fj["Fc"], field + ".Fc");
    if (fj.contains("beta")) f.beta = rd.number(fj["beta"], field + ".beta");
    f.Fs = fj.contains("Fs") ? rd.number(fj["Fs"], field + ".Fs") : f.Fc;
    if (fj.contains("qds")) f.qds = rd.number(fj["qds"], field + ".qds", true);
  }
}

void read_joint_names(const Reader& rd, const json& j, RobotDescription& r) {
  const json* names = nullptr;
  std::string field = "joint_names";
  if (j.contains("joint_names")) {
    names = &j["joint_names"];
  } else if (j.contains("source") && j["source"].is_object() && j["source"].contains("joints")) {
    names = &j["source"]["joints"];
    field = "source.joints";
  }
  if (!names) return;
  if (!names->is_array() || static_cast<int>(names->size()) != r.num_joints)
    rd.fail(field, "expected a list of " + std::to_string(r.num_joints) + " joint names (one per joint)");
  for (size_t k = 0; k < names->size(); ++k) {
    const json& n = (*names)[k];
    if (!n.is_string() || n.get<std::string>().empty())
      rd.fail(field + "[" + std::to_string(k + 1) + "]", "expected a joint's name");
    for (const auto& before : r.joint_names)
      if (before == n.get<std::string>()) rd.fail(field + "[" + std::to_string(k + 1) + "]", "'" + before + "' twice");
    r.joint_names.push_back(n.get<std::string>());
  }
}

void read_log_formats(const Reader& rd, const json& j, RobotDescription& r) {
  if (!j.contains("log_formats")) return;
  const json& f = j["log_formats"];
  if (!f.is_array()) rd.fail("log_formats", "expected a list of log format names (--format)");
  for (size_t k = 0; k < f.size(); ++k) {
    if (!f[k].is_string() || f[k].get<std::string>().empty())
      rd.fail("log_formats[" + std::to_string(k + 1) + "]", "expected a log format's name (--format)");
    r.log_formats.push_back(f[k].get<std::string>());
  }
}

}  // namespace

bool is_prismatic(const RobotDescription& robot, int j) {
  return j >= 0 && static_cast<size_t>(j) < robot.prismatic.size() && robot.prismatic[static_cast<size_t>(j)];
}
const char* effort_unit(const RobotDescription& robot, int j) {
  return is_prismatic(robot, j) ? "N" : "Nm";
}

std::string default_robots_dir() {
  if (const char* env = std::getenv("DYNCAL_ROBOTS")) return env;
  return source_tree_dir() + "/robots";
}

std::string default_robot_name(const std::string& robots_dir) {
  const std::string path = robots_dir + "/default.txt";
  std::ifstream in(path);
  std::string line;
  while (in && std::getline(in, line)) {
    const auto b = line.find_first_not_of(" \t\r");
    if (b == std::string::npos || line[b] == '#') continue;
    const std::string name = line.substr(b, line.find_last_not_of(" \t\r") + 1 - b);
    if (!std::filesystem::is_regular_file(robots_dir + "/" + name + "/robot.json"))
      throw InputError(path + " names robot '" + name + "', which has no folder there: give --robot");
    return name;
  }
  throw InputError("no --robot given, and " + path + " names no default robot: give --robot");
}

std::string robot_for_log_format(const std::string& robots_dir, const std::string& format) {
  std::vector<std::string> found;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(robots_dir, ec)) {
    const auto file = entry.path() / "robot.json";
    std::ifstream in(file);
    if (!in) continue;
    const json j = json::parse(in, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("log_formats") || !j["log_formats"].is_array()) continue;
    for (const auto& f : j["log_formats"])
      if (f.is_string() && f.get<std::string>() == format) found.push_back(entry.path().filename().string());
  }
  std::sort(found.begin(), found.end());
  if (found.empty())
    throw InputError("--robot is required for --format " + format + " (no robot under " + robots_dir +
                     " lists it in its log_formats)");
  if (found.size() > 1)
    throw InputError("robots " + found[0] + " and " + found[1] + " under " + robots_dir + " both list log format " +
                     format + ": give --robot");
  return found[0];
}

RobotDescription load_robot(const std::string& robots_dir, const std::string& name) {
  const std::string path = robots_dir + "/" + name + "/robot.json";
  const json j = read_json(name, path);
  const Reader rd{path};
  if (!j.is_object()) throw InputError(path + ": the file is not a JSON object");
  RobotDescription r;
  r.name = name;
  r.directory = robots_dir + "/" + name;
  if (!j.contains("name") || !j["name"].is_string()) rd.fail("name", "missing (the robot's name, as its folder)");
  if (j["name"].get<std::string>() != name)
    rd.fail("name", "'" + j["name"].get<std::string>() + "' differs from the folder name '" + name + "'");
  read_limits(rd, j, r);
  read_kinematics(rd, j, r);
  read_transmission(rd, j, r);
  read_friction(rd, j, r);
  read_joint_names(rd, j, r);
  read_log_formats(rd, j, r);
  return r;
}

}  // namespace dyncal::host
