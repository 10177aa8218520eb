#include "dyncal_host/drive/scenario.hpp"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/model_effects.hpp"

namespace dyncal::host {
namespace {

using nlohmann::json;

json read_json(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot read " + path);
  try {
    json j;
    in >> j;
    return j;
  } catch (const json::exception& e) {
    throw InputError(path + ": invalid JSON: " + e.what());
  }
}

double number(const json& j, const char* key, double fallback, const std::string& where) {
  if (!j.contains(key)) return fallback;
  if (!j[key].is_number()) throw InputError(where + ": '" + key + "' must be a number");
  const double v = j[key].get<double>();
  if (!std::isfinite(v)) throw InputError(where + ": '" + key + "' is not finite");
  return v;
}

void read_joint(const json& j, JointFriction& f, JointEffects& e, const std::string& where) {
  if (!j.is_object()) throw InputError(where + " must be an object");
  if (j.contains("friction")) {
    const json& fj = j["friction"];
    const std::string w = where + ".friction";
    if (fj.contains("model")) f.model = parse_friction_model(fj["model"].get<std::string>());
    f.Fc = number(fj, "Fc", f.Fc, w);
    f.beta = number(fj, "beta", f.beta, w);
    f.Fs = number(fj, "Fs", f.Fs, w);
    f.qds = number(fj, "qds", f.qds, w);
    f.delta_s = number(fj, "delta_s", f.delta_s, w);
    f.f1 = number(fj, "f1", f.f1, w);
    f.f2 = number(fj, "f2", f.f2, w);
    f.f3 = number(fj, "f3", f.f3, w);
    f.f4 = number(fj, "f4", f.f4, w);
    f.f5 = number(fj, "f5", f.f5, w);
    f.fp = number(fj, "fp", f.fp, w);
    f.fl = number(fj, "fl", f.fl, w);
    if (f.qds <= 0 || f.f3 <= 0 || f.f5 <= 0) throw InputError(w + ": qds, f3 and f5 must be > 0");
  }
  if (j.contains("cogging")) {
    const json& c = j["cogging"];
    e.cogging_amplitude = number(c, "amplitude", 0, where + ".cogging");
    e.cogging_cycles = number(c, "cycles_per_rev", 0, where + ".cogging");
    e.cogging_phase = number(c, "phase", 0, where + ".cogging");
  }
  e.load_friction = number(j, "load_friction", e.load_friction, where);
  if (j.contains("viscous_drift")) {
    e.viscous_drift = number(j["viscous_drift"], "relative_rise", 0, where + ".viscous_drift");
    e.drift_time_constant = number(j["viscous_drift"], "time_constant", 600, where + ".viscous_drift");
    if (e.drift_time_constant <= 0) throw InputError(where + ".viscous_drift.time_constant must be > 0");
  }
  e.offset = number(j, "offset", e.offset, where);
  e.rotor_inertia = number(j, "rotor_inertia", e.rotor_inertia, where);
  if (e.rotor_inertia < 0) throw InputError(where + ".rotor_inertia must be >= 0");
}

/// A list of n numbers >= 0 under `key` of the drive.json `j`, or false when absent.
bool joint_list(const json& j, const char* key, int n, const std::string& path,
                std::array<double, kMaxDriveJoints>& out) {
  if (!j.contains(key)) return false;
  const json& a = j[key];
  if (!a.is_array() || static_cast<int>(a.size()) != n)
    throw InputError(path + ": " + key + ": expected " + std::to_string(n) + " numbers (one per joint)");
  for (int k = 0; k < n; ++k) {
    const std::string field = std::string(key) + "[" + std::to_string(k + 1) + "]";
    const json& v = a[static_cast<size_t>(k)];
    if (!v.is_number() || !std::isfinite(v.get<double>()) || v.get<double>() < 0)
      throw InputError(path + ": " + field + ": expected a number >= 0");
    out[static_cast<size_t>(k)] = v.get<double>();
  }
  return true;
}

}  // namespace

MotorMap identity_motor_map() {
  MotorMap T{};
  for (int m = 0; m < kMaxDriveJoints; ++m) T[static_cast<size_t>(m)][static_cast<size_t>(m)] = 1.0;
  return T;
}

Scenario default_scenario(const RobotDescription& robot) {
  if (robot.num_joints < 1 || robot.num_joints > kMaxDriveJoints)
    throw InputError("the simulated drive runs 1 to " + std::to_string(kMaxDriveJoints) + " joints, '" + robot.name +
                     "' has " + std::to_string(robot.num_joints));
  Scenario s;
  s.robot = robot.name;
  s.num_joints = robot.num_joints;
  const Eigen::MatrixXd T = motor_velocity_map(robot, true, {});
  for (int m = 0; m < robot.num_joints; ++m)
    for (int j = 0; j < robot.num_joints; ++j) s.motor_map[static_cast<size_t>(m)][static_cast<size_t>(j)] = T(m, j);
  std::array<double, kMaxDriveJoints> motor_inertia{};
  bool noise_given = false;
  const std::string drive_file = robot.directory + "/drive.json";
  if (std::ifstream(drive_file)) {
    const json d = read_json(drive_file);
    if (!d.is_object()) throw InputError(drive_file + ": expected an object");
    joint_list(d, "motor_inertia", robot.num_joints, drive_file, motor_inertia);
    noise_given = joint_list(d, "tau_noise_std", robot.num_joints, drive_file, s.tau_noise_std);
  }
  for (int j = 0; j < robot.num_joints; ++j) {
    if (!noise_given)
      s.tau_noise_std[j] =
          robot.tau_max.size() == robot.num_joints ? kDefaultNoiseFractionOfTauMax * robot.tau_max[j] : 0.0;
    const NominalFriction f =
        static_cast<size_t>(j) < robot.friction.size() ? robot.friction[static_cast<size_t>(j)] : NominalFriction{};
    s.friction[j].Fc = f.Fc;
    s.friction[j].beta = f.beta;
    s.friction[j].Fs = f.Fs;
    s.friction[j].qds = f.qds;
    const double n = robot.gear_ratios[j];
    s.effects[j].rotor_inertia = motor_inertia[j] * n * n;
  }
  return s;
}

namespace {

/// The scenario's "couplings": friction that couples two joints. Throws InputError naming `w` (the file).
void read_couplings(const json& value, const std::string& w, Scenario& s) {
  for (const json& c : value) {
    CoupledFriction cf;
    if (!c.contains("joints") || c["joints"].size() != 2) throw InputError(w + ": a coupling needs \"joints\": [i, j]");
    cf.joint_i = c["joints"][0].get<int>() - 1;
    cf.joint_j = c["joints"][1].get<int>() - 1;
    if (cf.joint_i < 0 || cf.joint_j < 0 || cf.joint_i >= s.num_joints || cf.joint_j >= s.num_joints ||
        cf.joint_i == cf.joint_j) {
      throw InputError(w + ": coupling joints must be two different joints 1.." + std::to_string(s.num_joints));
    }
    cf.sign = number(c, "sign", 1.0, w + ".couplings");
    cf.Fc = number(c, "Fc", 0, w + ".couplings");
    cf.beta = number(c, "beta", 0, w + ".couplings");
    s.couplings.push_back(cf);
  }
}

/// The scenario's "payload" {mass, com, inertia_about_com} on the last link. Throws InputError naming `w` (the file).
void read_payload(const json& value, const std::string& w, Scenario& s) {
  const json& pl = value;
  const std::string where = w + ": payload";
  if (!pl.is_object()) throw InputError(where + " must be an object {mass, com, inertia_about_com}");
  s.payload.mass = number(pl, "mass", 0.0, where);
  if (!(s.payload.mass >= 0) || !std::isfinite(s.payload.mass)) throw InputError(where + ".mass must be >= 0");
  auto list = [&](const char* key, double* out, size_t n) {
    if (!pl.contains(key)) return;
    const json& a = pl[key];
    if (!a.is_array() || a.size() != n)
      throw InputError(where + "." + key + " must be " + std::to_string(n) + " numbers");
    for (size_t k = 0; k < n; ++k) {
      if (!a[k].is_number() || !std::isfinite(a[k].get<double>()))
        throw InputError(where + "." + key + " must be " + std::to_string(n) + " numbers");
      out[k] = a[k].get<double>();
    }
  };
  list("com", s.payload.com.data(), 3);
  list("inertia_about_com", s.payload.inertia.data(), 6);
}

/// The scenario's "contacts": external forces on links, each for a time. Throws InputError naming `w` (the file).
void read_contacts(const json& value, const std::string& w, Scenario& s) {
  const json& cs = value;
  if (!cs.is_array()) throw InputError(w + ": contacts must be an array of objects");
  for (size_t k = 0; k < cs.size(); ++k) {
    const json& c = cs[k];
    const std::string where = w + ": contacts[" + std::to_string(k + 1) + "]";
    if (!c.is_object()) throw InputError(where + " must be an object {link, point, force, start, duration}");
    ExternalContact e;
    if (!c.contains("link") || !c["link"].is_number_integer() || c["link"].get<int>() < 1 ||
        c["link"].get<int>() > s.num_joints)
      throw InputError(where + ".link must be a link 1.." + std::to_string(s.num_joints));
    e.link = c["link"].get<int>();
    auto vec3 = [&](const char* key, std::array<double, 3>& out) {
      if (!c.contains(key)) return;
      const json& a = c[key];
      if (!a.is_array() || a.size() != 3) throw InputError(where + "." + key + " must be 3 numbers");
      for (size_t i = 0; i < 3; ++i) {
        if (!a[i].is_number() || !std::isfinite(a[i].get<double>()))
          throw InputError(where + "." + key + " must be 3 numbers");
        out[i] = a[i].get<double>();
      }
    };
    vec3("point", e.point);
    vec3("force", e.force);
    e.start = number(c, "start", 0.0, where);
    e.duration = number(c, "duration", 0.0, where);
    e.stiffness = number(c, "stiffness", 0.0, where);
    if (!(e.start >= 0) || !(e.duration > 0) || !(e.stiffness >= 0))
      throw InputError(where + ": start must be >= 0, duration > 0, stiffness >= 0");
    if (e.force[0] == 0 && e.force[1] == 0 && e.force[2] == 0)
      throw InputError(where + ".force must not be zero (with a stiffness: its direction)");
    s.contacts.push_back(e);
  }
}

/// The scenario's "stop_and_go" {move, rest, ramp}: a trajectory played with rests. Throws InputError naming `w` (the
/// file).
void read_stop_and_go(const json& value, const std::string& w, Scenario& s) {
  const json& g = value;
  const std::string where = w + ": stop_and_go";
  if (!g.is_object()) throw InputError(where + " must be an object {move, rest, ramp}");
  s.stop_and_go.move = number(g, "move", s.stop_and_go.move, where);
  s.stop_and_go.rest = number(g, "rest", 1.5, where);
  s.stop_and_go.ramp = number(g, "ramp", s.stop_and_go.ramp, where);
  if (!(s.stop_and_go.rest > 0) || !s.stop_and_go.valid())
    throw InputError(where + ": ramp must be > 0, move and rest >= ramp [s]");
}

}  // namespace

Scenario load_scenario(const std::string& path, const RobotDescription& robot) {
  Scenario s = default_scenario(robot);
  const json j = read_json(path);
  const std::string w = path;
  if (j.contains("robot") && j["robot"].get<std::string>() != robot.name) {
    throw InputError(w + ": scenario is for robot '" + j["robot"].get<std::string>() + "', drive runs '" + robot.name +
                     "'");
  }
  s.seed = static_cast<std::uint64_t>(number(j, "seed", static_cast<double>(s.seed), w));
  s.control_rate_hz = number(j, "control_rate_hz", s.control_rate_hz, w);
  s.substeps = static_cast<int>(number(j, "substeps", s.substeps, w));
  s.sample_rate_hz = number(j, "sample_rate_hz", s.sample_rate_hz, w);
  s.bandwidth_hz = number(j, "bandwidth_hz", s.bandwidth_hz, w);
  s.damping = number(j, "damping", s.damping, w);
  s.encoder_counts = number(j, "encoder_counts", s.encoder_counts, w);
  if (s.control_rate_hz < 1000 || s.substeps < 1 || s.encoder_counts < 0) {
    throw InputError(w + ": control_rate_hz must be >= 1000, substeps >= 1, encoder_counts >= 0 (0: no quantisation)");
  }
  if (j.contains("tau_noise_std")) {
    const json& a = j["tau_noise_std"];
    if (a.is_number()) {
      s.tau_noise_std.fill(a.get<double>());
    } else if (a.is_array() && static_cast<int>(a.size()) == s.num_joints) {
      for (int k = 0; k < s.num_joints; ++k) s.tau_noise_std[k] = a[static_cast<size_t>(k)].get<double>();
    } else {
      throw InputError(w + ": tau_noise_std must be a number or an array of " + std::to_string(s.num_joints));
    }
  }
  if (j.contains("couplings")) read_couplings(j["couplings"], w, s);
  if (j.contains("payload")) read_payload(j["payload"], w, s);
  if (j.contains("contacts")) read_contacts(j["contacts"], w, s);
  if (j.contains("stiction")) {
    if (!j["stiction"].is_boolean()) throw InputError(w + ": stiction must be true or false");
    s.stiction = j["stiction"].get<bool>();
  }
  if (j.contains("stop_and_go")) read_stop_and_go(j["stop_and_go"], w, s);
  if (j.contains("joints")) {
    const json& js = j["joints"];
    if (!js.is_array() || static_cast<int>(js.size()) != s.num_joints)
      throw InputError(w + ": 'joints' must be an array of " + std::to_string(s.num_joints) + " objects");
    for (int k = 0; k < s.num_joints; ++k) {
      read_joint(js[static_cast<size_t>(k)], s.friction[k], s.effects[k],
                 w + ": joints[" + std::to_string(k + 1) + "]");
    }
  }
  return s;
}

double friction_torque(const JointFriction& f, double qd, double tau_load) {
  const double sg = qd > 0 ? 1.0 : (qd < 0 ? -1.0 : 0.0);
  const double aq = std::fabs(qd);
  switch (f.model) {
    case FrictionModel::eq4:
      return (f.Fc + (f.Fs - f.Fc) * std::exp(-std::pow(aq / f.qds, f.delta_s))) * sg + f.beta * qd;
    case FrictionModel::eq5:
      return f.f1 * sg - f.f2 * sg * std::exp(-aq / f.f3) - (aq > 0 ? f.f4 * sg * std::exp(-1.0 / (f.f5 * aq)) : 0.0) +
             f.beta * qd;
    case FrictionModel::eq6:
      return (f.f1 + f.f2 / std::cosh(f.f3 * qd)) * std::tanh(f.f4 * qd) + f.beta * qd;
    case FrictionModel::eq7:
      return f.Fc * sg + f.beta * qd;
    case FrictionModel::eq8:
      return f.Fc * sg + f.beta * qd + f.fp * std::cbrt(qd);
    case FrictionModel::eq9:
      return f.Fc * sg + f.beta * qd + f.fl * std::fabs(tau_load) * sg;
  }
  return 0.0;
}

}  // namespace dyncal::host
