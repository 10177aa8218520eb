#include "dyncal_host/model/drive_table.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>

#include "dyncal/parameter_table.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/normal_quantile.hpp"
#include "dyncal_host/model/compiled_robot.hpp"

namespace dyncal::host {
namespace {

/// A motor's terms, by name prefix: Coulomb, viscous friction, rotor inertia (a coupling term's c[0..2];
/// what a drive refuses below 0).
constexpr const char* kMotorTerms[3] = {"Fc", "Fv", "Ia"};

bool is_motor_term(const std::string& name) {
  return std::any_of(std::begin(kMotorTerms), std::end(kMotorTerms),
                     [&name](const char* prefix) { return name.rfind(prefix, 0) == 0; });
}

/// Whether compiled parameter i is a motor term (Fc, Fv, Ia) below 0 by less than its 95 % interval
/// (kZ95 std, identify's std): the data do not tell it from 0.
bool negative_within_noise(const ParameterSet& p, size_t i) {
  const Eigen::Index k = static_cast<Eigen::Index>(i);
  return is_motor_term(p.names[i]) && p.values[k] < 0.0 && k < p.stdev.size() && std::isfinite(p.stdev[k]) &&
         -p.values[k] <= kZ95 * p.stdev[k];
}

/// Index of parameter `name` among the compiled ones (the first `count`), or -1.
int index_of(const ParameterSet& p, const std::string& name, size_t count) {
  for (size_t i = 0; i < count; ++i)
    if (p.names[i] == name) return static_cast<int>(i);
  return -1;
}

}  // namespace

DriveTableContent drive_table_content(const ParameterSet& p, const RobotDescription& robot) {
  if (p.robot != robot.name)
    throw InputError(p.source + ": parameters are for robot '" + p.robot + "', not '" + robot.name + "'");
  const size_t count = compiled_parameter_count(p);
  DriveTableContent out;
  out.values.assign(p.values.data(), p.values.data() + count);
  // A negative Coulomb, viscous or rotor-inertia term that its own 95 % interval does not set apart
  // from 0 is 0 as far as the data say, and a drive refuses a negative one: the table holds 0.
  for (size_t i = 0; i < count; ++i)
    if (negative_within_noise(p, i)) {
      char line[200];
      std::snprintf(line, sizeof line,
                    "%s = %.3g +- %.2g (std): 0 within its 95 %% interval, held at 0 in the drive table (a drive "
                    "takes no negative friction or rotor inertia)",
                    p.names[i].c_str(), p.values[static_cast<Eigen::Index>(i)], p.stdev[static_cast<Eigen::Index>(i)]);
      out.notes.push_back(line);
      out.values[i] = 0.0;
    }
  const int n = robot.num_joints;
  const Eigen::MatrixXd T = motor_velocity_map(robot, p.friction_per_motor, p.motors);
  for (int m = 0; m < n; ++m) {
    std::vector<int> others;
    for (int j = 0; j < n; ++j)
      if (j != m && T(m, j) != 0.0) others.push_back(j);
    if (others.empty()) continue;
    const std::string motor = std::to_string(m + 1);
    if (others.size() > 1)
      throw InputError(p.source + ": motor " + motor +
                       " turns with several other joints; a table's coupling term couples two (flash a file "
                       "identified with --friction-per-joint)");
    const int j = others.front();
    const int fp = index_of(p, "Fp" + motor, count);
    if (fp >= 0 && out.values[static_cast<size_t>(fp)] != 0.0)
      throw InputError(p.source + ": Eq. 8 power friction of coupled motor " + motor + " has no table term");
    const double r = T(m, j);
    EffectTerm t;
    t.kind = EffectKind::coupling;
    t.joint = static_cast<std::uint8_t>(m);
    t.joint2 = static_cast<std::uint8_t>(j);
    t.sign = static_cast<std::int8_t>(r > 0 ? 1 : -1);
    t.shape = static_cast<float>(std::abs(r));
    for (int c = 0; c < 3; ++c) {
      const int i = index_of(p, kMotorTerms[c] + motor, count);
      if (i < 0) continue;
      t.c[c] = static_cast<float>(out.values[static_cast<size_t>(i)]);
      out.values[static_cast<size_t>(i)] = 0.0;
    }
    out.effects.push_back(t);
    char line[160];
    std::snprintf(line, sizeof line,
                  "motor %d (turns with q%d %+g q%d): its friction and rotor inertia as a coupling term", m + 1, m + 1,
                  r, j + 1);
    out.notes.push_back(line);
  }
  size_t k = count;
  for (const ModelEffect& e : p.effects) {
    if (e.kind == EffectKind::shape)  // a spline: no 20-byte table term holds it
      out.notes.push_back("shape of " + e.variable + " on joint " + std::to_string(e.joint + 1) +
                          ": not in the table (a table term holds no spline); the drive's feed-forward goes without "
                          "it");
    else
      out.effects.push_back(effect_term(e, p.values.data() + k));
    k += effect_param_names(e).size();
  }
  if (out.effects.size() > static_cast<size_t>(kTableMaxEffects))
    throw InputError(p.source + ": " + std::to_string(out.effects.size()) + " effect terms, a table holds " +
                     std::to_string(kTableMaxEffects));
  return out;
}

ParameterTable parameter_table(const ParameterSet& p, const RobotDescription& robot, std::vector<std::string>* notes) {
  const DriveTableContent content = drive_table_content(p, robot);
  const size_t count = compiled_parameter_count(p);
  // What a drive refuses (lib/ table_check.hpp: friction opposes motion, inertia is positive),
  // named here, before any drive is contacted; a coupled motor's terms too, which the table holds as
  // a coupling term's coefficients.
  for (size_t i = 0; i < count; ++i) {
    const std::string& name = p.names[i];
    if (is_motor_term(name) && p.values[static_cast<Eigen::Index>(i)] < 0.0 && !negative_within_noise(p, i)) {
      char value[32];
      std::snprintf(value, sizeof value, "%.6g", p.values[static_cast<Eigen::Index>(i)]);
      throw InputError(
          p.source + ": params[" + std::to_string(i + 1) + "] '" + name + "' = " + value +
          ": Coulomb and viscous friction and rotor inertia must be >= 0 in a drive table, and this one is "
          "below 0 beyond its 95 % interval (or has no std): the data contradict physics there (identify "
          "--sign-constraints holds them at 0)");
    }
  }
  ParameterTable t;
  t.robot_id = compiled_robot(p.robot).robot_id;
  t.model_id = p.terms;
  if (content.values.size() > static_cast<size_t>(kTableMaxParams))
    throw InputError("robot '" + p.robot + "': more params than a table holds");
  t.count = static_cast<std::uint16_t>(content.values.size());
  for (size_t i = 0; i < content.values.size(); ++i) {
    if (std::fabs(content.values[i]) > 3.4e38)
      throw InputError("params[" + std::to_string(i + 1) + "] '" + p.names[i] + "': value " +
                       std::to_string(content.values[i]) + " is not a finite float");
    t.values[i] = static_cast<float>(content.values[i]);
  }
  for (size_t i = 0; i < content.effects.size(); ++i) {
    for (float c : content.effects[i].c)
      if (!std::isfinite(c)) throw InputError("an effect coefficient is not a finite float");
    t.effects[i] = content.effects[i];
  }
  t.effect_count = static_cast<std::uint16_t>(content.effects.size());
  if (notes) notes->insert(notes->end(), content.notes.begin(), content.notes.end());
  return t;
}

}  // namespace dyncal::host
