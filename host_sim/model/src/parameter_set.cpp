#include "dyncal_host/model/parameter_set.hpp"

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/json_file.hpp"
#include "dyncal_host/model/compiled_robot.hpp"

namespace dyncal::host {
namespace {

/// The file's "torque_constants": {source, values [N] finite and nonzero, std [N] null or >= 0}.
void read_torque_constants(const nlohmann::json& t, const std::string& path, int joints, ParameterSet& p) {
  const std::string what = path + ": 'torque_constants' ";
  if (!t.is_object() || !t.contains("values") || !t["values"].is_array() ||
      t["values"].size() != static_cast<size_t>(joints))
    throw InputError(what + "must hold 'values', one per motor (" + std::to_string(joints) + ")");
  p.torque_constants.resize(joints);
  p.torque_constants_std = Eigen::VectorXd::Constant(joints, std::numeric_limits<double>::quiet_NaN());
  const nlohmann::json none = nlohmann::json::array();
  const nlohmann::json& sd = t.contains("std") && t["std"].is_array() ? t["std"] : none;
  if (!sd.empty() && sd.size() != static_cast<size_t>(joints)) throw InputError(what + "'std' must have one per motor");
  for (int k = 0; k < joints; ++k) {
    const nlohmann::json& v = t["values"][static_cast<size_t>(k)];
    if (!v.is_number() || !std::isfinite(v.get<double>()) || v.get<double>() == 0.0)
      throw InputError(what + "value " + std::to_string(k + 1) + " is not a finite nonzero number");
    p.torque_constants[k] = v.get<double>();
    if (sd.empty() || sd[static_cast<size_t>(k)].is_null()) continue;
    if (!sd[static_cast<size_t>(k)].is_number() || !(sd[static_cast<size_t>(k)].get<double>() >= 0.0))
      throw InputError(what + "std " + std::to_string(k + 1) + " is not a number >= 0");
    p.torque_constants_std[k] = sd[static_cast<size_t>(k)].get<double>();
  }
  p.torque_constants_source = t.value("source", std::string("the parameter file"));
}

/// The "links" (one per joint, in order): finite numbers, mass > 0. Throws InputError.
std::vector<LinkInertial> read_links(const nlohmann::json& list, const std::string& path, int joints) {
  if (!list.is_array() || static_cast<int>(list.size()) != joints)
    throw InputError(path + ": 'links' must list the " + std::to_string(joints) + " links");
  std::vector<LinkInertial> out;
  for (size_t k = 0; k < list.size(); ++k) {
    const auto& e = list[k];
    const std::string where = path + ": links[" + std::to_string(k + 1) + "]";
    auto number = [&](const nlohmann::json& v, const std::string& what) {
      if (!v.is_number() || !std::isfinite(v.get<double>()))
        throw InputError(where + ": '" + what + "' is not a finite number");
      return v.get<double>();
    };
    if (!e.is_object() || !e.contains("mass") || !e.contains("com") || !e.contains("inertia_about_com") ||
        !e["com"].is_array() || e["com"].size() != 3 || !e["inertia_about_com"].is_array() ||
        e["inertia_about_com"].size() != 6)
      throw InputError(where + ": expected {mass, com[3], inertia_about_com[6]}");
    LinkInertial l;
    l.link = static_cast<int>(k) + 1;
    l.mass = number(e["mass"], "mass");
    if (!(l.mass > 0)) throw InputError(where + ": mass must be > 0");
    for (int i = 0; i < 3; ++i) l.com[static_cast<size_t>(i)] = number(e["com"][static_cast<size_t>(i)], "com");
    for (int i = 0; i < 6; ++i)
      l.inertia[static_cast<size_t>(i)] = number(e["inertia_about_com"][static_cast<size_t>(i)], "inertia_about_com");
    if (e.contains("pseudo_inertia_min_eigenvalue") && e["pseudo_inertia_min_eigenvalue"].is_number())
      l.min_eigenvalue = e["pseudo_inertia_min_eigenvalue"].get<double>();
    // Their std (optional; null or absent: none).
    const auto sd = [&](const char* key, size_t i, size_t n) {
      if (!e.contains(key)) return LinkInertial::kNoStd;
      const nlohmann::json& v = n == 1 ? e[key] : (e[key].is_array() && e[key].size() == n ? e[key][i] : e[key]);
      if (v.is_null()) return LinkInertial::kNoStd;
      if (!v.is_number() || !(v.get<double>() >= 0.0))
        throw InputError(where + ": '" + key + "' must be numbers >= 0 (or null)");
      return v.get<double>();
    };
    l.mass_std = sd("mass_std", 0, 1);
    if (e.contains("mass_basis") && e["mass_basis"].is_string()) l.mass_basis = e["mass_basis"].get<std::string>();
    for (size_t i = 0; i < 3; ++i) l.com_std[i] = sd("com_std", i, 3);
    for (size_t i = 0; i < 6; ++i) l.inertia_std[i] = sd("inertia_std", i, 6);
    out.push_back(l);
  }
  return out;
}

}  // namespace

ParameterSet read_parameter_file(const std::string& path) {
  const nlohmann::json j = read_json_file(path);
  if (!j.is_object() || j.value("format", "") != "dyncal-parameters")
    throw InputError(path + ": not a dyncal parameter file (\"format\": \"dyncal-parameters\")");
  if (!j.contains("robot") || !j["robot"].is_string()) throw InputError(path + ": 'robot' missing");
  if (!j.contains("model") || !j["model"].is_string()) throw InputError(path + ": 'model' missing");
  ParameterSet p;
  p.source = path;
  p.robot = j["robot"].get<std::string>();
  p.model = j["model"].get<std::string>();
  const std::string per =
      j.contains("friction_per") && j["friction_per"].is_string() ? j["friction_per"].get<std::string>() : "joint";
  if (per != "joint" && per != "motor")
    throw InputError(path + ": 'friction_per' is '" + per + "', expected 'joint' or 'motor'");
  p.friction_per_motor = per == "motor";
  const CompiledRobot& compiled = compiled_robot(p.robot);
  try {
    const ModelSpec spec = parse_model_spec(p.model, compiled.num_joints);
    p.terms = spec.terms;
    p.effects = spec.effects;
    p.motors = spec.motors;
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.what());
  }
  p.names = term_set_model(compiled, p.terms).names;
  for (const ModelEffect& e : p.effects)
    for (const std::string& n : effect_param_names(e)) p.names.push_back(n);
  // Checked by name, so that a file edited by hand or written for another model cannot give
  // shifted values.
  if (!j.contains("params") || !j["params"].is_array()) throw InputError(path + ": 'params' missing");
  const auto& list = j["params"];
  if (list.size() != p.names.size())
    throw InputError(path + ": " + std::to_string(list.size()) + " params, robot '" + p.robot + "' with model '" +
                     p.model + "' has " + std::to_string(p.names.size()));
  p.values.resize(static_cast<Eigen::Index>(list.size()));
  p.stdev = Eigen::VectorXd::Constant(p.values.size(), std::nan(""));
  for (size_t i = 0; i < list.size(); ++i) {
    const auto& v = list[i];
    const std::string where = path + ": params[" + std::to_string(i + 1) + "]";
    if (!v.is_object() || !v.contains("value") || !v["value"].is_number())
      throw InputError(where + ": expected an object with a number 'value'");
    if (!v.contains("name") || !v["name"].is_string()) throw InputError(where + ": 'name' missing");
    if (v["name"].get<std::string>() != p.names[i])
      throw InputError(where + " is '" + v["name"].get<std::string>() + "', parameter " + std::to_string(i + 1) +
                       " of robot '" + p.robot + "' with model '" + p.model + "' is '" + p.names[i] + "'");
    const double value = v["value"].get<double>();
    if (!std::isfinite(value)) throw InputError(where + " '" + p.names[i] + "': value is not finite");
    p.values[static_cast<Eigen::Index>(i)] = value;
    if (v.contains("std") && v["std"].is_number() && std::isfinite(v["std"].get<double>()) &&
        v["std"].get<double>() >= 0)
      p.stdev[static_cast<Eigen::Index>(i)] = v["std"].get<double>();
  }
  if (j.contains("tau_model_reference")) {
    const auto& ref = j["tau_model_reference"];
    if (!ref.is_array() || ref.size() != list.size())
      throw InputError(path + ": 'tau_model_reference' must hold " + std::to_string(list.size()) + " numbers");
    p.tau_model_reference.resize(p.values.size());
    for (size_t i = 0; i < ref.size(); ++i) {
      if (!ref[i].is_number() || !std::isfinite(ref[i].get<double>()))
        throw InputError(path + ": tau_model_reference[" + std::to_string(i + 1) + "] is not a finite number");
      p.tau_model_reference[static_cast<Eigen::Index>(i)] = ref[i].get<double>();
    }
  }
  for (const ModelEffect& e : p.effects)
    if (shape_of_tau_model(e) && p.tau_model_reference.size() == 0)
      throw InputError(path + ": the shape of " + e.variable + " needs 'tau_model_reference' (the model it reads)");
  if (j.contains("links")) p.links = read_links(j["links"], path, compiled.num_joints);
  if (j.contains("torque_constants")) read_torque_constants(j["torque_constants"], path, compiled.num_joints, p);
  return p;
}

nlohmann::json parameter_file_json(const ParameterSet& p, const std::string& method) {
  nlohmann::json j;
  j["format"] = "dyncal-parameters";
  j["version"] = 1;
  j["robot"] = p.robot;
  j["model"] = p.model;
  j["method"] = method;
  // "motor": a coupled motor's friction and rotor inertia act on every joint that turns it (the
  // drive's feed-forward cannot apply that yet); "joint": per joint, as the drive applies them.
  j["friction_per"] = p.friction_per_motor ? "motor" : "joint";
  j["params"] = nlohmann::json::array();
  // The std lets a later step (payload) carry the parameters' uncertainty; null where not determined.
  const bool with_std = p.stdev.size() == p.values.size();
  for (Eigen::Index i = 0; i < p.values.size(); ++i) {
    nlohmann::json e = {{"name", p.names[static_cast<size_t>(i)]}, {"value", p.values[i]}};
    if (with_std) e["std"] = p.stdev[i];
    j["params"].push_back(e);
  }
  if (p.tau_model_reference.size() > 0)
    j["tau_model_reference"] =
        std::vector<double>(p.tau_model_reference.data(), p.tau_model_reference.data() + p.tau_model_reference.size());
  if (!p.links.empty()) j["links"] = link_inertials_json(p.links);
  if (p.torque_constants.size() > 0) j["torque_constants"] = torque_constants_json(p);
  return j;
}

nlohmann::json torque_constants_json(const ParameterSet& p) {
  nlohmann::json sd = nlohmann::json::array();
  for (Eigen::Index k = 0; k < p.torque_constants_std.size(); ++k)
    sd.push_back(std::isfinite(p.torque_constants_std[k]) ? nlohmann::json(p.torque_constants_std[k])
                                                          : nlohmann::json(nullptr));
  return {
      {"source", p.torque_constants_source},
      {"values", std::vector<double>(p.torque_constants.data(), p.torque_constants.data() + p.torque_constants.size())},
      {"std", sd}};
}

nlohmann::json link_inertials_json(const std::vector<LinkInertial>& links) {
  nlohmann::json out = nlohmann::json::array();
  const auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  for (const auto& l : links) {
    nlohmann::json e = {{"link", l.link},
                        {"mass", l.mass},
                        {"com", l.com},
                        {"inertia_about_com", l.inertia},
                        {"pseudo_inertia_min_eigenvalue", l.min_eigenvalue}};
    if (!l.mass_basis.empty()) {
      e["mass_std"] = number(l.mass_std);
      e["mass_basis"] = l.mass_basis;
      e["com_std"] = nlohmann::json::array();
      for (double v : l.com_std) e["com_std"].push_back(number(v));
      e["inertia_std"] = nlohmann::json::array();
      for (double v : l.inertia_std) e["inertia_std"].push_back(number(v));
    }
    out.push_back(e);
  }
  return out;
}

ParameterSet parameter_set(const IdentifyResult& r) {
  ParameterSet p;
  p.robot = r.robot;
  p.model = r.model;
  const ModelSpec spec = parse_model_spec(r.model, static_cast<int>(r.joints.size()));
  p.terms = spec.terms;
  p.effects = spec.effects;
  p.motors = spec.motors;
  p.friction_per_motor = r.friction_per_motor;
  p.source = "identify";
  p.values.resize(static_cast<Eigen::Index>(r.params.size()));
  p.stdev.resize(p.values.size());
  for (size_t i = 0; i < r.params.size(); ++i) {
    p.names.push_back(r.params[i].name);
    p.values[static_cast<Eigen::Index>(i)] = r.params[i].value;
    p.stdev[static_cast<Eigen::Index>(i)] = r.params[i].std;
  }
  p.links = r.links;
  p.tau_model_reference = Eigen::Map<const Eigen::VectorXd>(r.tau_model_reference.data(),
                                                            static_cast<Eigen::Index>(r.tau_model_reference.size()));
  return p;
}

size_t compiled_parameter_count(const ParameterSet& p) {
  size_t count = p.names.size();
  for (const ModelEffect& e : p.effects) count -= effect_param_names(e).size();
  return count;
}

ParameterSet without_time_shapes(ParameterSet p, std::vector<std::string>* notes) {
  Eigen::Index k = static_cast<Eigen::Index>(compiled_parameter_count(p));
  for (const ModelEffect& e : p.effects) {
    const Eigen::Index m = static_cast<Eigen::Index>(effect_param_names(e).size());
    if (shape_of_time(e)) {
      p.values.segment(k, m).setZero();
      if (notes)
        notes->push_back("shape of " + e.variable + " on joint " + std::to_string(e.joint + 1) +
                         ": a change over the identification log, not applied to this log");
    }
    k += m;
  }
  return p;
}

}  // namespace dyncal::host
