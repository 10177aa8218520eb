#include "dyncal_host/common/model_effects.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/json_file.hpp"
#include "dyncal_host/common/model_terms.hpp"
#include "dyncal_host/common/spline_basis.hpp"

namespace dyncal::host {
namespace {

struct KindInfo {
  EffectKind kind;
  const char* name;
  bool needs_shape;
};

constexpr KindInfo kKinds[] = {
    {EffectKind::stribeck, "stribeck", true},
    {EffectKind::asymmetric_friction, "asymmetric_friction", false},
    {EffectKind::velocity_power, "velocity_power", false},
    {EffectKind::load_friction, "load_friction", false},
    {EffectKind::rotor_inertia, "rotor_inertia", false},
    {EffectKind::offset, "offset", false},
    {EffectKind::position_periodic, "position_periodic", true},
    {EffectKind::coupling, "coupling", false},
    {EffectKind::shape, "shape", false},
};

const KindInfo* find_kind(const std::string& name) {
  for (const KindInfo& k : kKinds)
    if (name == k.name) return &k;
  return nullptr;
}

const KindInfo& info(EffectKind kind) {
  for (const KindInfo& k : kKinds)
    if (k.kind == kind) return k;
  return kKinds[5];
}

std::string kind_list() {
  std::string out;
  for (const KindInfo& k : kKinds) out += std::string(out.empty() ? "" : ", ") + k.name;
  return out;
}

/// A 1-based joint number of 1..N from `text`, or -1.
int joint_number(const std::string& text, int num_joints) {
  if (text.empty() || text.size() > 2 || text.find_first_not_of("0123456789") != std::string::npos) return -1;
  const int j = std::atoi(text.c_str());
  return j >= 1 && j <= num_joints ? j : -1;
}

std::string J(int j) {
  return std::to_string(j + 1);
}

/// A coupling's ratio |r| (shape; 0 means 1).
double ratio(const ModelEffect& e) {
  return e.shape > 0 ? e.shape : 1.0;
}

bool same_effect(const ModelEffect& a, const ModelEffect& b) {
  if (a.kind != b.kind || a.joint != b.joint) return false;
  if (a.kind == EffectKind::shape) return a.variable == b.variable;
  if (a.kind == EffectKind::coupling) return a.joint2 == b.joint2 && a.sign == b.sign && ratio(a) == ratio(b);
  return a.shape == b.shape;
}

/// "coupled_motor:M+J[:RATIO]" (1-based) into a CoupledMotor; throws InputError naming `where`.
CoupledMotor parse_coupled_motor(const std::string& rest, const std::string& ratio_text, bool has_ratio, int num_joints,
                                 const std::string& where) {
  const size_t op = rest.find_first_of("+-");
  const int a = op == std::string::npos ? -1 : joint_number(rest.substr(0, op), num_joints);
  const int b = op == std::string::npos ? -1 : joint_number(rest.substr(op + 1), num_joints);
  if (a < 0 || b < 0)
    throw InputError(where + ": expected coupled_motor:M+J or coupled_motor:M-J with joints 1.." +
                     std::to_string(num_joints));
  if (a == b) throw InputError(where + ": a motor coupled with its own joint");
  double r = 1.0;
  if (has_ratio) {
    char* end = nullptr;
    r = std::strtod(ratio_text.c_str(), &end);
    if (ratio_text.empty() || *end != '\0' || !std::isfinite(r) || !(r > 0))
      throw InputError(where + ": the ratio after a second ':' must be a positive number");
  }
  return {a - 1, b - 1, rest[op] == '+' ? r : -r};
}

/// A shape's full knot vector checked: finite, the boundaries four times each, the rest strictly
/// increasing inside them, at least 3 columns (8 knots). Throws InputError naming `where`.
void check_shape_knots(const std::vector<double>& k, const std::string& where) {
  bool ok = k.size() >= 8;
  for (size_t i = 0; ok && i < k.size(); ++i) ok = std::isfinite(k[i]);
  for (size_t i = 1; ok && i < 4; ++i) ok = k[i] == k[0] && k[k.size() - 1 - i] == k.back();
  for (size_t i = 4; ok && i + 3 < k.size(); ++i) ok = k[i] > k[i - 1];
  if (!ok)
    throw InputError(where + ": a shape's knots must be finite, increasing, at least 8 with each boundary 4 times");
}

/// "shape:J:VARIABLE:K0/K1/.../Kn[:LAMBDA]" after "shape:" into a shape effect; throws InputError
/// naming `where`.
ModelEffect parse_shape_item(const std::string& rest, int num_joints, const std::string& where) {
  const size_t a = rest.find(':'), b = a == std::string::npos ? a : rest.find(':', a + 1);
  if (b == std::string::npos) throw InputError(where + ": expected shape:J:VARIABLE:K0/K1/.../Kn[:LAMBDA]");
  const size_t c = rest.find(':', b + 1);
  ModelEffect e;
  e.kind = EffectKind::shape;
  const int j = joint_number(rest.substr(0, a), num_joints);
  if (j < 0) throw InputError(where + ": joint '" + rest.substr(0, a) + "' is not 1.." + std::to_string(num_joints));
  e.joint = j - 1;
  e.variable = rest.substr(a + 1, b - a - 1);
  parse_shape_variable(e.variable, e.joint, num_joints);
  if (c != std::string::npos) {
    const std::string lambda = rest.substr(c + 1);
    char* end = nullptr;
    e.penalty = std::strtod(lambda.c_str(), &end);
    if (lambda.empty() || *end != '\0' || !std::isfinite(e.penalty) || e.penalty < 0)
      throw InputError(where + ": a shape's penalty '" + lambda + "' is not a finite number >= 0");
  }
  std::stringstream list(rest.substr(b + 1, c == std::string::npos ? c : c - b - 1));
  std::string number;
  std::vector<double> distinct;
  while (std::getline(list, number, '/')) {
    char* end = nullptr;
    distinct.push_back(std::strtod(number.c_str(), &end));
    if (number.empty() || *end != '\0') throw InputError(where + ": knot '" + number + "' is not a number");
  }
  if (distinct.size() < 2) throw InputError(where + ": a shape needs at least its two boundary knots");
  e.knots.assign(3, distinct.front());
  e.knots.insert(e.knots.end(), distinct.begin(), distinct.end());
  e.knots.insert(e.knots.end(), 3, distinct.back());
  check_shape_knots(e.knots, where);
  return e;
}

/// The full knot vector of the union of two shapes' knots: boundaries the wider of the two (four
/// times each), interior knots both shapes' strictly inside them.
std::vector<double> union_of_knots(const std::vector<double>& a, const std::vector<double>& b) {
  const double lo = std::min(a.front(), b.front()), hi = std::max(a.back(), b.back());
  std::vector<double> inner;
  for (const std::vector<double>* k : {&a, &b})
    for (size_t i = 4; i + 4 < k->size(); ++i)
      if ((*k)[i] > lo && (*k)[i] < hi) inner.push_back((*k)[i]);
  std::sort(inner.begin(), inner.end());
  inner.erase(std::unique(inner.begin(), inner.end()), inner.end());
  std::vector<double> out(4, lo);
  out.insert(out.end(), inner.begin(), inner.end());
  out.insert(out.end(), 4, hi);
  return out;
}

/// A shape's variable as a parameter-name tag: sgn(qdJ)*X becomes sgn_X.
std::string shape_tag(const ModelEffect& e) {
  const size_t star = e.variable.find('*');
  return star == std::string::npos ? e.variable : "sgn_" + e.variable.substr(star + 1);
}

/// A diagnosis report's shape entry on joint `joint` (0-based): its "variable" and "knots", checked.
/// Throws InputError naming `where`.
ModelEffect read_shape_entry(const nlohmann::json& x, int joint, int num_joints, const std::string& where) {
  ModelEffect e;
  e.kind = EffectKind::shape;
  e.joint = joint;
  if (!x.contains("variable") || !x["variable"].is_string()) throw InputError(where + ": a shape needs its 'variable'");
  e.variable = x["variable"].get<std::string>();
  try {
    parse_shape_variable(e.variable, e.joint, num_joints);
  } catch (const InputError& error) {
    throw InputError(where + ": " + error.what());
  }
  if (!x.contains("knots") || !x["knots"].is_array()) throw InputError(where + ": a shape needs its 'knots'");
  for (const auto& k : x["knots"]) {
    if (!k.is_number()) throw InputError(where + ": a shape's knots must be numbers");
    e.knots.push_back(k.get<double>());
  }
  check_shape_knots(e.knots, where);
  if (x.contains("penalty")) {
    if (!x["penalty"].is_number() || !std::isfinite(x["penalty"].get<double>()) || x["penalty"].get<double>() < 0)
      throw InputError(where + ": a shape's 'penalty' must be a finite number >= 0");
    e.penalty = x["penalty"].get<double>();
  }
  return e;
}

/// Appends shape e to out.effects, or, when out has a shape of the same variable on the same joint
/// (the diagnosis refining it with other knots), widens that one to the union of their knots (the
/// sum of two cubic splines is one on the union) and says so in *skipped.
void add_diagnosed_shape(const ModelEffect& e, ModelSpec& out, std::vector<std::string>* skipped) {
  auto same = std::find_if(out.effects.begin(), out.effects.end(), [&e](const ModelEffect& o) {
    return o.kind == EffectKind::shape && o.joint == e.joint && o.variable == e.variable;
  });
  if (same == out.effects.end()) {
    out.effects.push_back(e);
    return;
  }
  same->knots = union_of_knots(same->knots, e.knots);
  same->penalty = std::min(same->penalty, e.penalty);
  if (skipped)
    skipped->push_back("shape of " + e.variable + " on joint " + std::to_string(e.joint + 1) +
                       " found twice: one shape on the union of their knots");
}

}  // namespace

ShapeVariable parse_shape_variable(const std::string& name, int joint, int num_joints) {
  const std::string where = "shape variable '" + name + "'", own = J(joint);
  ShapeVariable v;
  v.joint = joint;
  std::string rest = name;
  if (rest.rfind("sgn(", 0) == 0) {
    const std::string prefix = "sgn(qd" + own + ")*";
    if (rest.rfind(prefix, 0) != 0)
      throw InputError(where + ": a sign product on joint " + own + " is " + prefix + "X");
    v.times_sign = true;
    rest = rest.substr(prefix.size());
  }
  if (rest == "t") return v;
  const std::pair<const char*, ShapeVariable::Of> forms[] = {{"tau_model", ShapeVariable::Of::tau_model},
                                                             {"qdd", ShapeVariable::Of::qdd},
                                                             {"qd", ShapeVariable::Of::qd},
                                                             {"q", ShapeVariable::Of::q}};
  for (const auto& [prefix, of] : forms) {
    const std::string p = prefix;
    if (rest.rfind(p, 0) != 0) continue;
    const int k = joint_number(rest.substr(p.size()), num_joints);
    if (k < 0) break;
    if (of == ShapeVariable::Of::tau_model && k - 1 != joint)
      throw InputError(where + ": a shape on joint " + own + " reads tau_model" + own + " only");
    v.of = of;
    v.joint = k - 1;
    return v;
  }
  throw InputError(where + ": expected t, qK, qdK, qddK (K 1.." + std::to_string(num_joints) + "), tau_model" + own +
                   " or sgn(qd" + own + ")* one of them");
}

std::string coupled_motor_item(const CoupledMotor& m) {
  std::string out = "coupled_motor:" + J(m.motor) + (m.ratio > 0 ? "+" : "-") + J(m.with);
  if (std::abs(m.ratio) != 1.0) {
    char number[32];
    std::snprintf(number, sizeof number, ":%.17g", std::abs(m.ratio));
    out += number;
  }
  return out;
}

Eigen::MatrixXd motor_velocity_map(const RobotDescription& robot, bool robot_transmission,
                                   const std::vector<CoupledMotor>& motors) {
  const int n = robot.num_joints;
  Eigen::MatrixXd T = Eigen::MatrixXd::Identity(n, n);
  if (robot_transmission && robot.transmission.rows() == n && robot.transmission.cols() == n &&
      (robot.transmission.diagonal().array() != 0.0).all()) {
    for (int m = 0; m < n; ++m) T.row(m) = robot.transmission.row(m) / robot.transmission(m, m);
  }
  for (const CoupledMotor& c : motors) {
    T.row(c.motor).setZero();
    T(c.motor, c.motor) = 1.0;
    T(c.motor, c.with) = c.ratio;
  }
  return T;
}

const char* effect_kind_name(EffectKind k) {
  return info(k).name;
}

std::string effect_item(const ModelEffect& e) {
  std::string out = std::string(effect_kind_name(e.kind)) + ":" + J(e.joint);
  if (e.kind == EffectKind::coupling) out += (e.sign > 0 ? "+" : "-") + J(e.joint2);
  if (e.kind == EffectKind::shape) {
    out += ":" + e.variable + ":";
    for (size_t k = 3; k + 3 < e.knots.size(); ++k) {
      char number[32];
      std::snprintf(number, sizeof number, "%s%.17g", k == 3 ? "" : "/", e.knots[k]);
      out += number;
    }
    if (e.penalty > 0) {
      char number[32];
      std::snprintf(number, sizeof number, ":%.17g", e.penalty);
      out += number;
    }
    return out;
  }
  if (info(e.kind).needs_shape || (e.kind == EffectKind::coupling && ratio(e) != 1.0)) {
    char number[32];
    std::snprintf(number, sizeof number, ":%.17g", e.shape);
    out += number;
  }
  return out;
}

std::vector<std::string> effect_param_names(const ModelEffect& e) {
  const std::string j = J(e.joint);
  switch (e.kind) {
    case EffectKind::stribeck:
      return {"Fs" + j};
    case EffectKind::asymmetric_friction:
      return {"Fc+" + j, "Fv+" + j};
    case EffectKind::velocity_power:
      return {"Fp" + j};
    case EffectKind::load_friction:
      return {"Fl" + j};
    case EffectKind::rotor_inertia:
      return {"Ia" + j};
    case EffectKind::offset:
      return {"offset" + j};
    case EffectKind::position_periodic:
      return {"A" + j + "_sin", "A" + j + "_cos"};
    case EffectKind::coupling: {
      const std::string tag = j + (e.sign > 0 ? "+" : "-") + J(e.joint2);
      return {"Fc" + tag, "Fv" + tag, "Ia" + tag};
    }
    case EffectKind::shape: {
      std::vector<std::string> names;
      // Numbered as the basis functions they come from: after the first (left out) from 2; a shape
      // without its linear part mixes them all (spline_basis.hpp), from 1.
      const bool without_linear = shape_without_linear(e.variable);
      const int m = shape_basis_columns(e.knots, without_linear);
      for (int b = 0; b < m; ++b)
        names.push_back("shape" + j + "_" + shape_tag(e) + "_" + std::to_string(b + (without_linear ? 1 : 2)));
      return names;
    }
  }
  return {};
}

EffectTerm effect_term(const ModelEffect& e, const double* coefficients) {
  EffectTerm t;
  t.kind = e.kind;
  t.joint = static_cast<std::uint8_t>(e.joint);
  if (e.kind == EffectKind::coupling) {
    t.joint2 = static_cast<std::uint8_t>(e.joint2);
    t.sign = static_cast<std::int8_t>(e.sign > 0 ? 1 : -1);
  }
  t.shape = static_cast<float>(e.shape);
  const size_t m = effect_param_names(e).size();
  for (size_t k = 0; k < m && k < 3; ++k) t.c[k] = static_cast<float>(coefficients[k]);
  return t;
}

ModelSpec parse_model_spec(const std::string& model, int num_joints) {
  ModelSpec spec;
  std::vector<std::pair<ModelEffect, std::string>> effects;
  std::string terms_only;
  std::stringstream ss(model);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const size_t colon = item.find(':');
    if (colon == std::string::npos) {
      terms_only += item + ",";
      continue;
    }
    const std::string where = "model item '" + item + "'";
    if (item.substr(0, colon) == "coupled_motor") {
      const std::string rest = item.substr(colon + 1);
      const size_t colon2 = rest.find(':');
      const CoupledMotor m =
          parse_coupled_motor(rest.substr(0, colon2), colon2 == std::string::npos ? "" : rest.substr(colon2 + 1),
                              colon2 != std::string::npos, num_joints, where);
      for (const CoupledMotor& o : spec.motors)
        if (o.motor == m.motor) throw InputError(where + ": motor " + J(m.motor) + " coupled twice");
      spec.motors.push_back(m);
      continue;
    }
    if (item.substr(0, colon) == "shape") {
      effects.emplace_back(parse_shape_item(item.substr(colon + 1), num_joints, where), where);
      continue;
    }
    const KindInfo* k = find_kind(item.substr(0, colon));
    if (!k) throw InputError(where + ": unknown effect (expected one of " + kind_list() + ", coupled_motor)");
    std::string rest = item.substr(colon + 1), shape_text;
    const size_t colon2 = rest.find(':');
    if (colon2 != std::string::npos) {
      shape_text = rest.substr(colon2 + 1);
      rest = rest.substr(0, colon2);
    }
    ModelEffect e;
    e.kind = k->kind;
    if (k->kind == EffectKind::coupling) {
      const size_t op = rest.find_first_of("+-");
      const int a = op == std::string::npos ? -1 : joint_number(rest.substr(0, op), num_joints);
      const int b = op == std::string::npos ? -1 : joint_number(rest.substr(op + 1), num_joints);
      if (a < 0 || b < 0)
        throw InputError(where + ": expected coupling:I+J or coupling:I-J with joints 1.." +
                         std::to_string(num_joints));
      if (a == b) throw InputError(where + ": a joint coupled with itself");
      e.joint = a - 1;
      e.joint2 = b - 1;
      e.sign = rest[op] == '+' ? 1 : -1;
    } else {
      const int a = joint_number(rest, num_joints);
      if (a < 0) throw InputError(where + ": joint '" + rest + "' is not 1.." + std::to_string(num_joints));
      e.joint = a - 1;
    }
    if (k->needs_shape) {
      char* end = nullptr;
      e.shape = shape_text.empty() ? 0.0 : std::strtod(shape_text.c_str(), &end);
      if (shape_text.empty() || *end != '\0' || !std::isfinite(e.shape) || !(e.shape > 0))
        throw InputError(where + ": needs a positive " +
                         (k->kind == EffectKind::stribeck ? std::string("velocity scale [rad/s]")
                                                          : std::string("number of cycles per revolution")) +
                         " after a second ':'");
    } else if (k->kind == EffectKind::coupling && colon2 != std::string::npos) {
      char* end = nullptr;
      e.shape = std::strtod(shape_text.c_str(), &end);
      if (shape_text.empty() || *end != '\0' || !std::isfinite(e.shape) || !(e.shape > 0))
        throw InputError(where + ": the ratio after a second ':' must be a positive number");
    } else if (colon2 != std::string::npos) {
      throw InputError(where + ": " + k->name + " takes no shape");
    }
    effects.emplace_back(e, where);
  }
  spec.terms = parse_model(terms_only);
  if (!spec.motors.empty() && !(spec.terms & (term::coulomb | term::viscous | term::rotor_inertia)))
    throw InputError("model item '" + coupled_motor_item(spec.motors.front()) +
                     "': a coupled motor takes over its joint's friction and rotor-inertia terms, and the model has "
                     "none (add eq7)");
  for (const auto& [e, where] : effects) add_effect(spec, e, where);
  return spec;
}

bool model_contains(const ModelSpec& spec, const ModelEffect& e) {
  if (e.kind == EffectKind::rotor_inertia && (spec.terms & term::rotor_inertia)) return true;
  if (e.kind == EffectKind::offset && (spec.terms & term::offset)) return true;
  for (const ModelEffect& o : spec.effects)
    if (same_effect(o, e)) return true;
  return false;
}

void add_effect(ModelSpec& spec, const ModelEffect& e, const std::string& where) {
  if (e.kind == EffectKind::rotor_inertia && (spec.terms & term::rotor_inertia))
    throw InputError(where + ": the model's rotor_inertia term already gives every joint its Ia");
  if (e.kind == EffectKind::offset && (spec.terms & term::offset))
    throw InputError(where + ": the model's offset term already gives every joint an offset");
  if (model_contains(spec, e)) throw InputError(where + ": the same effect twice");
  spec.effects.push_back(e);
}

std::string model_spec_name(const ModelSpec& spec) {
  std::string out = model_name(spec.terms);
  for (const ModelEffect& e : spec.effects) out += "," + effect_item(e);
  for (const CoupledMotor& m : spec.motors) out += "," + coupled_motor_item(m);
  return out;
}

std::vector<TorqueDelay> parse_torque_delays(const std::string& text, int num_joints) {
  std::vector<TorqueDelay> out;
  std::stringstream items(text);
  std::string item;
  while (std::getline(items, item, ',')) {
    const size_t colon = item.find(':');
    int joint = 0;
    double seconds = 0;
    try {
      size_t used = 0;
      if (colon == std::string::npos) throw std::invalid_argument(item);
      joint = std::stoi(item.substr(0, colon), &used);
      if (used != colon) throw std::invalid_argument(item);
      seconds = std::stod(item.substr(colon + 1), &used);
      if (used != item.size() - colon - 1) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw InputError("--torque-delay: '" + item + "' is not JOINT:SECONDS (e.g. 3:0.004)");
    }
    if (joint < 1 || joint > num_joints)
      throw InputError("--torque-delay: joint " + std::to_string(joint) + " is not 1.." + std::to_string(num_joints));
    if (!std::isfinite(seconds))
      throw InputError("--torque-delay: the delay of joint " + std::to_string(joint) + " is not finite");
    for (const TorqueDelay& d : out)
      if (d.joint == joint - 1) throw InputError("--torque-delay: joint " + std::to_string(joint) + " given twice");
    out.push_back({joint - 1, seconds});
  }
  return out;
}

ModelSpec read_diagnosed_effects(const std::string& path, int num_joints, std::vector<std::string>* skipped,
                                 std::vector<TorqueDelay>* delays) {
  const nlohmann::json j = read_json_file(path);
  if (!j.is_object() || !j.contains("declared_model") || !j.contains("effects") || !j["effects"].is_array())
    throw InputError(path + ": not a dyncal diagnose report (\"declared_model\" and \"effects\")");
  ModelSpec out;
  for (size_t i = 0; i < j["effects"].size(); ++i) {
    const nlohmann::json& x = j["effects"][i];
    const std::string where = path + ": effects[" + std::to_string(i + 1) + "]";
    if (!x.is_object() || !x.contains("kind") || !x["kind"].is_string())
      throw InputError(where + ": expected an object with a 'kind'");
    const std::string name = x["kind"].get<std::string>();
    if (!x.contains("joints") || !x["joints"].is_array() || x["joints"].empty())
      throw InputError(where + ": 'joints' missing");
    std::vector<int> joints;
    for (const auto& v : x["joints"]) {
      if (!v.is_number_integer() || v.get<int>() < 1 || v.get<int>() > num_joints)
        throw InputError(where + ": joints must be 1.." + std::to_string(num_joints));
      joints.push_back(v.get<int>() - 1);
    }
    // A torque channel's delay: undone on the log (logs/torque_delay.hpp), not a model term.
    if (name == "torque_delay" && delays) {
      if (!x.contains("shape") || !x["shape"].is_number() || !std::isfinite(x["shape"].get<double>()))
        throw InputError(where + ": a torque delay needs a finite 'shape' (its delay [s])");
      delays->push_back({joints.front(), x["shape"].get<double>()});
      continue;
    }
    if (name == "shape") {
      add_diagnosed_shape(read_shape_entry(x, joints.front(), num_joints, where), out, skipped);
      continue;
    }
    // Not a model term: drift (a change over the log): skipped and named.
    if (name == "drift" || name == "torque_delay") {
      if (skipped)
        skipped->push_back(name + " on joint " + std::to_string(joints.front() + 1) +
                           " has no model term (not fitted)");
      continue;
    }
    if (name == "coupled_motor") {
      if (joints.size() != 2 || joints[0] == joints[1])
        throw InputError(where + ": a coupled motor needs two joints (its own, then the other)");
      const double shape =
          x.contains("shape") && x["shape"].is_number() && x["shape"].get<double>() > 0 ? x["shape"].get<double>() : 1;
      out.motors.push_back({joints[0], joints[1], x.value("sign", 1.0) < 0 ? -shape : shape});
      continue;
    }
    const KindInfo* k = find_kind(name);
    if (!k)
      throw InputError(where + ": unknown kind '" + name + "' (expected one of " + kind_list() +
                       ", coupled_motor, drift, torque_delay)");
    ModelEffect e;
    e.kind = k->kind;
    e.joint = joints.front();
    if (k->kind == EffectKind::coupling) {
      if (joints.size() != 2 || joints[0] == joints[1]) throw InputError(where + ": a coupling needs two joints");
      e.joint2 = joints[1];
      e.sign = x.value("sign", 1.0) < 0 ? -1 : 1;
      e.shape =
          x.contains("shape") && x["shape"].is_number() && x["shape"].get<double>() > 0 ? x["shape"].get<double>() : 0;
    }
    if (k->needs_shape) {
      if (!x.contains("shape") || !x["shape"].is_number() || !(x["shape"].get<double>() > 0))
        throw InputError(where + ": '" + name + "' needs a positive 'shape'");
      e.shape = x["shape"].get<double>();
    }
    out.effects.push_back(e);
  }
  return out;
}

}  // namespace dyncal::host
