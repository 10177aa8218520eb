// Gates on a command's JSON report (gate.hpp, docs/gates.md).
#include "dyncal_host/report/gate.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <functional>
#include <limits>
#include <sstream>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Measured {
  int joint = 0;
  std::string what;
  double value = kNaN;
};

using Measure = std::function<std::vector<Measured>(const nlohmann::json& report)>;

struct KeyDef {
  std::string key, meaning, bound;  // bound: ">=" or "<="
  Measure measure;
};

double number(const nlohmann::json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_number() ? j[key].get<double>() : kNaN;
}

/// Per joint: report[section][k][field], section "joints".
Measure per_joint(std::string field, std::string what, std::string within = "") {
  return [=](const nlohmann::json& report) {
    const nlohmann::json& r = within.empty() ? report : report.value(within, nlohmann::json::object());
    std::vector<Measured> out;
    if (r.contains("joints") && r["joints"].is_array())
      for (const auto& j : r["joints"])
        out.push_back({j.value("joint", 0), "joint " + std::to_string(j.value("joint", 0)) + " " + what,
                       number(j, field.c_str())});
    if (out.empty()) out.push_back({0, what + " (the report has no joints)", kNaN});
    return out;
  };
}

Measure scalar(std::string field, std::string what, std::string within = "") {
  return [=](const nlohmann::json& report) {
    const nlohmann::json& r = within.empty() ? report : report.value(within, nlohmann::json::object());
    return std::vector<Measured>{{0, what, number(r, field.c_str())}};
  };
}

Measure count(std::string field, std::string what) {
  return [=](const nlohmann::json& report) {
    const bool has = report.contains(field) && report[field].is_array();
    return std::vector<Measured>{{0, what, has ? static_cast<double>(report[field].size()) : kNaN}};
  };
}

Measure not_determined(std::string within = "") {
  return [=](const nlohmann::json& report) {
    const nlohmann::json& r = within.empty() ? report : report.value(within, nlohmann::json::object());
    double n = 0;
    for (const auto& p : r.value("params", nlohmann::json::array()))
      if (p.value("verdict", "").rfind("not determined", 0) == 0) ++n;
    return std::vector<Measured>{{0, "parameters not determined by the log", n}};
  };
}

/// Physics: each link's pseudo-inertia smallest eigenvalue (>= 0: a rigid body), and each rotor
/// inertia, Coulomb, Stribeck and viscous friction's upper 95 % bound (>= 0: the data do not
/// contradict a non-negative value).
Measure physics(std::string within = "") {
  return [=](const nlohmann::json& report) {
    const nlohmann::json& r = within.empty() ? report : report.value(within, nlohmann::json::object());
    std::vector<Measured> out;
    for (const auto& l : r.value("links", nlohmann::json::array()))
      out.push_back({0, "link " + std::to_string(l.value("link", 0)) + " pseudo-inertia's smallest eigenvalue",
                     number(l, "pseudo_inertia_min_eigenvalue")});
    for (const auto& p : r.value("params", nlohmann::json::array())) {
      const std::string name = p.value("name", "");
      if (name.rfind("Ia", 0) != 0 && name.rfind("Fc", 0) != 0 && name.rfind("Fv", 0) != 0 && name.rfind("Fs", 0) != 0)
        continue;
      const double v = number(p, "value"), s = number(p, "std");
      out.push_back({0, name + "'s upper 95 % bound", std::isfinite(s) ? v + kZ95 * s : v});
    }
    if (out.empty()) out.push_back({0, "physical parameters (the report has none)", kNaN});
    return out;
  };
}

/// max(m / m_cad, m_cad / m) of each link: identified mass against the robot's CAD (robot.json) mass.
Measure mass_ratio(std::string within = "") {
  return [=](const nlohmann::json& report) {
    const nlohmann::json& r = within.empty() ? report : report.value(within, nlohmann::json::object());
    std::vector<Measured> out;
    for (const auto& l : r.value("links", nlohmann::json::array())) {
      const double m = number(l, "mass"), cad = number(l, "cad_mass");
      const double ratio = m > 0 && cad > 0 ? std::max(m / cad, cad / m) : kNaN;
      out.push_back({0, "link " + std::to_string(l.value("link", 0)) + " mass against its CAD mass (ratio)", ratio});
    }
    if (out.empty()) out.push_back({0, "link masses (the report has none: identify --method pcls gives them)", kNaN});
    return out;
  };
}

Measure payload_quantity(std::string name, bool std_dev) {
  return [=](const nlohmann::json& report) {
    for (const auto& q : report.value("quantities", nlohmann::json::array()))
      if (q.value("name", "") == name)
        return std::vector<Measured>{
            {0, "payload " + name + (std_dev ? " std" : ""), number(q, std_dev ? "std" : "value")}};
    return std::vector<Measured>{{0, "payload " + name + " (not in the report)", kNaN}};
  };
}

std::vector<KeyDef> fit_keys(const std::string& within) {
  return {
      {"r2_validation_min", "each joint's cross-validated R^2 at least this",
       ">=", per_joint("r2_validation", "cross-validated R^2", within)},
      {"rms_validation_max", "each joint's cross-validated RMS torque error [Nm] at most this",
       "<=", per_joint("rms_validation", "cross-validated RMS [Nm]", within)},
      {"relative_rms_validation_max", "each joint's cross-validated RMS relative to its RMS torque at most this",
       "<=", per_joint("relative_rms_validation", "relative cross-validated RMS", within)},
      {"condition_number_max", "the regressor's condition number at most this",
       "<=", scalar("condition_number", "condition number", within)},
      {"not_determined_max", "at most this many parameters not determined by the log", "<=", not_determined(within)},
      {"physics",
       "true: every link a rigid body (pseudo-inertia >= 0), no Ia, Fc, Fs, Fv negative beyond its 95 % interval",
       ">=", physics(within)},
      {"link_mass_ratio_max",
       "each link's identified mass within this factor of its CAD mass (robot.json), either way (pcls)",
       "<=", mass_ratio(within)},
  };
}

std::vector<KeyDef> keys_of(const std::string& command) {
  if (command == "identify") return fit_keys("");
  if (command == "predict") {
    auto keys = fit_keys("");
    keys.resize(3);  // the prediction's per-joint figures
    return keys;
  }
  if (command == "calibrate") {
    auto keys = fit_keys("batch");
    keys.push_back({"verify_rms_max",
                    "each joint's RMS on the fresh verification trajectory (batch fit) [Nm] at most this",
                    "<=", per_joint("verify_rms_batch", "verification RMS [Nm]")});
    return keys;
  }
  if (command == "diagnose")
    return {{"effects_max", "at most this many effects found beyond the declared model",
             "<=", count("effects", "effects found")},
            {"rms_validation_after_max", "each joint's cross-validated RMS after the found effects [Nm] at most this",
             "<=", per_joint("rms_validation_after", "cross-validated RMS after [Nm]")}};
  if (command == "payload")
    return {{"payload_mass_min", "the payload's mass [kg] at least this", ">=", payload_quantity("mass", false)},
            {"payload_mass_max", "the payload's mass [kg] at most this", "<=", payload_quantity("mass", false)},
            {"payload_mass_std_max", "the payload mass's standard deviation [kg] at most this",
             "<=", payload_quantity("mass", true)}};
  if (command == "monitor")
    return {{"contacts_max", "at most this many contacts found in the log", "<=", count("contacts", "contacts found")}};
  return {};
}

std::vector<double> parse_values(const std::string& text, const std::string& where) {
  std::vector<double> values;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    if (item == "true") {
      values.push_back(1.0);
      continue;
    }
    try {
      size_t used = 0;
      const double v = std::stod(item, &used);
      if (used != item.size() || !std::isfinite(v)) throw std::invalid_argument(item);
      values.push_back(v);
    } catch (const std::exception&) {
      throw InputError(where + ": '" + item + "' is not a finite number");
    }
  }
  if (values.empty()) throw InputError(where + ": no value");
  return values;
}

std::string known_keys(const std::string& command) {
  std::string s;
  for (const auto& k : keys_of(command)) s += (s.empty() ? "" : ", ") + k.key;
  return s;
}

void set_limit(Gate& gate, GateLimit limit) {
  bool known = false;
  for (const auto& k : keys_of(gate.command)) known = known || k.key == limit.key;
  if (!known)
    throw InputError(limit.source + ": '" + limit.key + "' is not a gate of " + gate.command +
                     " (its gates: " + known_keys(gate.command) + ")");
  for (auto& l : gate.limits)
    if (l.key == limit.key) {
      l = std::move(limit);
      return;
    }
  gate.limits.push_back(std::move(limit));
}

std::string scalar_text(const YAML::Node& n) {
  if (!n.IsScalar()) throw InputError("not a number");
  return n.Scalar();
}

}  // namespace

std::vector<std::pair<std::string, std::string>> gate_keys(const std::string& command) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& k : keys_of(command)) out.emplace_back(k.key, k.meaning);
  return out;
}

Gate read_gate(const std::string& command, const std::string& gate_file, const std::vector<std::string>& require) {
  Gate gate;
  gate.command = command;
  if (keys_of(command).empty() && (!gate_file.empty() || !require.empty())) throw InputError(command + " has no gates");
  if (!gate_file.empty()) {
    YAML::Node root;
    try {
      root = YAML::LoadFile(gate_file);
    } catch (const YAML::BadFile&) {
      throw InputError("cannot read gate file '" + gate_file + "'");
    } catch (const YAML::Exception& e) {
      throw InputError(gate_file + ": not YAML or JSON: " + e.msg + " (line " + std::to_string(e.mark.line + 1) + ")");
    }
    if (!root.IsMap())
      throw InputError(gate_file + ": a gate file is a map with a section per command (docs/gates.md)");
    const YAML::Node section = root[command];
    if (!section) throw InputError(gate_file + ": no '" + command + "' section (docs/gates.md)");
    if (!section.IsMap()) throw InputError(gate_file + ": '" + command + "' is not a map of gates");
    for (const auto& item : section) {
      const std::string key = item.first.as<std::string>();
      const std::string where = gate_file + ": " + command + "." + key;
      std::string text;
      try {
        if (item.second.IsSequence()) {
          for (const auto& v : item.second) text += (text.empty() ? "" : ",") + scalar_text(v);
        } else {
          text = scalar_text(item.second);
        }
      } catch (const InputError&) {
        throw InputError(where + ": a number, a list of numbers (one per joint) or true");
      }
      if (text == "false") continue;
      set_limit(gate, {key, parse_values(text, where), gate_file});
    }
  }
  for (const std::string& r : require) {
    const auto eq = r.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError("--require '" + r + "': KEY=VALUE (docs/gates.md; " + command +
                       "'s gates: " + known_keys(command) + ")");
    const std::string key = r.substr(0, eq), text = r.substr(eq + 1);
    if (text == "false") continue;
    set_limit(gate, {key, parse_values(text, "--require " + key), "--require"});
  }
  return gate;
}

GateResult evaluate_gate(const Gate& gate, const nlohmann::json& report) {
  GateResult result;
  const std::vector<KeyDef> keys = keys_of(gate.command);
  for (const GateLimit& limit : gate.limits) {
    const KeyDef* def = nullptr;
    for (const auto& k : keys)
      if (k.key == limit.key) def = &k;
    if (def == nullptr) throw InputError("internal: unknown gate '" + limit.key + "'");
    const std::vector<Measured> measured = def->measure(report);
    const bool per_joint_limit = limit.values.size() > 1;
    if (per_joint_limit && measured.size() != limit.values.size())
      throw InputError(limit.source + ": " + limit.key + " lists " + std::to_string(limit.values.size()) +
                       " values; the report has " + std::to_string(measured.size()) + " items to check");
    const bool physics = limit.key == "physics";
    for (size_t i = 0; i < measured.size(); ++i) {
      GateItem item;
      item.key = limit.key;
      item.joint = measured[i].joint;
      item.what = measured[i].what;
      item.value = measured[i].value;
      item.limit = physics ? 0.0 : limit.values[per_joint_limit ? i : 0];
      item.bound = def->bound;
      item.passed =
          std::isfinite(item.value) && (item.bound == ">=" ? item.value >= item.limit : item.value <= item.limit);
      result.passed = result.passed && item.passed;
      result.items.push_back(item);
    }
  }
  return result;
}

nlohmann::json gate_json(const GateResult& r) {
  nlohmann::json items = nlohmann::json::array();
  for (const GateItem& i : r.items)
    items.push_back({{"key", i.key},
                     {"joint", i.joint},
                     {"what", i.what},
                     {"value", std::isfinite(i.value) ? nlohmann::json(i.value) : nlohmann::json(nullptr)},
                     {"limit", i.limit},
                     {"bound", i.bound},
                     {"passed", i.passed}});
  return {{"passed", r.passed}, {"items", items}};
}

std::string gate_text(const GateResult& r) {
  size_t failed = 0;
  for (const GateItem& i : r.items) failed += i.passed ? 0 : 1;
  std::ostringstream s;
  s.precision(4);
  if (r.passed)
    s << "gate: passed (" << r.items.size() << " items)\n";
  else
    s << "gate: FAILED (" << failed << " of " << r.items.size() << " items)\n";
  for (const GateItem& i : r.items)
    if (!i.passed) {
      s << "  failed: " << i.key << ": " << i.what << " ";
      if (std::isfinite(i.value))
        s << i.value;
      else
        s << "(none)";
      s << ", required " << i.bound << " " << i.limit << "\n";
    }
  return s.str();
}

}  // namespace dyncal::host
