#include "dyncal_host/logs/column_map.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <map>
#include <utility>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/logs/numeric_csv.hpp"

namespace dyncal::host {
namespace {

/// Splits at commas outside braces (a range's braces hold none, but a stray one is reported there).
std::vector<std::string> entries(const std::string& spec) {
  std::vector<std::string> out;
  std::string cur;
  int depth = 0;
  for (const char c : spec) {
    if (c == '{') ++depth;
    if (c == '}') --depth;
    if (c == ',' && depth == 0) {
      out.push_back(trim_field(cur));
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(trim_field(cur));
  return out;
}

/// An integer of a range's bound, or false.
bool integer(const std::string& s, long& v) {
  if (s.empty()) return false;
  char* end = nullptr;
  errno = 0;
  v = std::strtol(s.c_str(), &end, 10);
  return end == s.c_str() + s.size() && errno != ERANGE;  // 99999999999999999999 is no joint number
}

/// The column names of `names`: one name, or a pattern with one {a..b} expanded to `joints` names
/// (`expand` false: one name, and a range is refused).
std::vector<std::string> column_names(const std::string& names, bool expand, int joints, const std::string& where) {
  const auto open = names.find('{');
  if (open == std::string::npos) {
    if (names.find('}') != std::string::npos) throw InputError(where + ": '}' without '{'");
    if (names.empty()) throw InputError(where + ": no column name");
    if (!expand) return {names};
    if (joints == 1) return {names};
    throw InputError(where + ": one column for " + std::to_string(joints) + " joints; give a range, e.g. " + names +
                     "{1.." + std::to_string(joints) + "}");
  }
  if (!expand) throw InputError(where + ": a range names several columns; this signal has one");
  const auto close = names.find('}', open);
  const auto dots = names.find("..", open);
  if (close == std::string::npos || dots == std::string::npos || dots > close ||
      names.find('{', open + 1) != std::string::npos)
    throw InputError(where + ": a range is {a..b}, once in a name");
  long a = 0, b = 0;
  if (!integer(names.substr(open + 1, dots - open - 1), a) || !integer(names.substr(dots + 2, close - dots - 2), b) ||
      a < 0 || a > b)
    throw InputError(where + ": a range is {a..b} with integers a <= b, a >= 0 (within a long's range)");
  if (b - a != joints - 1)
    throw InputError(where + ": {" + std::to_string(a) + ".." + std::to_string(b) + "} names " +
                     std::to_string(b - a + 1) + " columns, the robot has " + std::to_string(joints) + " joints");
  std::vector<std::string> out;
  for (long k = a; k <= b; ++k) out.push_back(names.substr(0, open) + std::to_string(k) + names.substr(close + 1));
  return out;
}

/// The factor from `unit` to the signal's SI unit, and whether the unit is linear (m, N: a prismatic
/// joint's) rather than angular (rad, Nm: a revolute joint's; time and current are both); or
/// InputError listing the signal's units.
double unit_scale(const std::string& signal, const std::string& unit, bool& current, bool& linear,
                  const std::string& where) {
  const double deg = M_PI / 180.0;
  struct Unit {
    const char* name;
    double factor;
    bool linear;
  };
  static const std::map<std::string, std::vector<Unit>> units{
      {"t", {{"s", 1.0, false}, {"ms", 1e-3, false}, {"us", 1e-6, false}, {"ns", 1e-9, false}}},
      {"q", {{"rad", 1.0, false}, {"deg", deg, false}, {"m", 1.0, true}, {"mm", 1e-3, true}}},
      {"qd", {{"rad/s", 1.0, false}, {"deg/s", deg, false}, {"m/s", 1.0, true}, {"mm/s", 1e-3, true}}},
      {"qdd", {{"rad/s^2", 1.0, false}, {"deg/s^2", deg, false}, {"m/s^2", 1.0, true}, {"mm/s^2", 1e-3, true}}},
      {"tau", {{"Nm", 1.0, false}, {"mNm", 1e-3, false}, {"N", 1.0, true}, {"current", 1.0, false}}},
  };
  const auto& list = units.at(signal);
  std::string known;
  for (const Unit& u : list) {
    if (u.name == unit) {
      current = unit == "current";
      linear = u.linear;
      return u.factor;
    }
    known += (known.empty() ? "" : ", ") + std::string(u.name);
  }
  throw InputError(where + ": unit '" + unit + "' is not one of " + known);
}

/// An example of both kinds' units for `signal` (q, qd, qdd or tau).
std::string mixed_unit_example(const std::string& signal) {
  if (signal == "tau") return "mNm|N";
  const std::string per = signal == "qd" ? "/s" : signal == "qdd" ? "/s^2" : "";
  return "deg" + per + "|mm" + per;
}

}  // namespace

ColumnMap parse_column_map(const std::string& spec, const std::vector<bool>& prismatic) {
  const int joints = static_cast<int>(prismatic.size());
  const bool any_prismatic = std::find(prismatic.begin(), prismatic.end(), true) != prismatic.end();
  const bool any_revolute = std::find(prismatic.begin(), prismatic.end(), false) != prismatic.end();
  ColumnMap map;
  map.origin = "--columns";
  map.prismatic = prismatic;
  std::map<std::string, bool> seen;
  for (const std::string& entry : entries(spec)) {
    const std::string where = "--columns '" + entry + "'";
    const auto eq = entry.find('=');
    if (eq == std::string::npos) throw InputError(where + ": expected signal=column[:unit]");
    const std::string signal = trim_field(entry.substr(0, eq));
    std::string names = trim_field(entry.substr(eq + 1)), unit;
    // The unit follows the last ':' outside the range (column names may hold none).
    const auto colon = names.rfind(':');
    if (colon != std::string::npos && names.find('}', colon) == std::string::npos) {
      unit = trim_field(names.substr(colon + 1));
      names = trim_field(names.substr(0, colon));
    }
    if (signal != "t" && signal != "q" && signal != "qd" && signal != "qdd" && signal != "tau")
      throw InputError(where + ": signal '" + signal + "' is not one of t, q, qd, qdd, tau");
    if (seen[signal]) throw InputError(where + ": " + signal + " is mapped twice");
    seen[signal] = true;
    // Up to two units, "angular|linear" (deg|mm): the revolute joints' and the prismatic joints'.
    double scale = 1.0, linear_scale = 1.0;
    bool current = false, have_angular = false, have_linear = false;
    for (std::string rest = unit; !rest.empty();) {
      const auto bar = rest.find('|');
      const std::string u = trim_field(rest.substr(0, bar));
      rest = bar == std::string::npos ? "" : rest.substr(bar + 1);
      bool is_current = false, linear = false;
      const double f = unit_scale(signal, u, is_current, linear, where);
      bool& have = linear ? have_linear : have_angular;
      if (have)
        throw InputError(where + ": two " + (linear ? "linear" : "angular") + " units; give one of each: deg|mm");
      have = true;
      (linear ? linear_scale : scale) = f;
      current = current || is_current;
    }
    if (signal != "t" && !current && (have_angular || have_linear)) {
      // Every unit given applies to some joint, and every joint gets a unit once one is given: a
      // unit that reads no joint, or a joint silently read in SI beside one that is not, is refused.
      if (have_linear && !any_prismatic)
        throw InputError(where + ": a linear unit, but the robot has no prismatic joint");
      if (have_angular && !any_revolute)
        throw InputError(where + ": an angular unit, but every joint of the robot is prismatic");
      if (any_prismatic && any_revolute && !(have_angular && have_linear))
        throw InputError(where + ": the robot has revolute and prismatic joints; give one unit of each kind, " +
                         "angular|linear (" + mixed_unit_example(signal) + ")");
    }
    if (signal == "t") {
      if (have_linear) throw InputError(where + ": a time unit is one of s, ms, us, ns");
      map.t = column_names(names, false, joints, where).front();
      map.t_scale = scale;
    } else {
      std::vector<std::string> cols = column_names(names, true, joints, where);
      if (current) linear_scale = scale;  // a current is a current on any joint
      if (signal == "q") map.q = std::move(cols), map.q_scale = scale, map.q_linear_scale = linear_scale;
      if (signal == "qd") map.qd = std::move(cols), map.qd_scale = scale, map.qd_linear_scale = linear_scale;
      if (signal == "qdd") map.qdd = std::move(cols), map.qdd_scale = scale, map.qdd_linear_scale = linear_scale;
      if (signal == "tau")
        map.effort = std::move(cols), map.effort_scale = scale, map.force_scale = linear_scale,
        map.effort_is_current = current;
    }
  }
  for (const char* required : {"t", "q", "tau"}) {
    if (!seen[required]) throw InputError("--columns: no " + std::string(required) + "=... entry");
  }
  return map;
}

ColumnMap ur_rtde_column_map(const std::vector<bool>& prismatic) {
  const int joints = static_cast<int>(prismatic.size());
  ColumnMap map = parse_column_map("t=timestamp, q=actual_q_{0.." + std::to_string(joints - 1) +
                                       "}, qd=actual_qd_{0.." + std::to_string(joints - 1) +
                                       "}, tau=actual_current_{0.." + std::to_string(joints - 1) + "}:current",
                                   prismatic);
  map.origin = "--format ur-rtde";
  return map;
}

JointLog read_mapped_csv_log(const std::string& path, const ColumnMap& map, int joints) {
  const NumericCsv csv = read_numeric_csv(path);
  std::map<std::string, Eigen::Index> col = column_index(csv, path);
  auto find = [&](const std::string& name) {
    const auto it = col.find(name);
    if (it == col.end()) throw InputError(path + ": no column '" + name + "' (" + map.origin + ")");
    return it->second;
  };
  auto block = [&](const std::vector<std::string>& names, double scale, double linear_scale) {
    Eigen::MatrixXd m(csv.values.rows(), joints);
    for (int j = 0; j < joints; ++j)
      m.col(j) = map.joint_scale(j, scale, linear_scale) * csv.values.col(find(names[static_cast<size_t>(j)]));
    return m;
  };
  JointLog log;
  log.source = path + " (" + map.origin + ")";
  log.t = map.t_scale * csv.values.col(find(map.t));
  log.q = block(map.q, map.q_scale, map.q_linear_scale);
  log.tau = block(map.effort, map.effort_scale, map.force_scale);
  log.has_qd = !map.qd.empty();
  log.has_qdd = !map.qdd.empty();
  if (log.has_qd) log.qd = block(map.qd, map.qd_scale, map.qd_linear_scale);
  if (log.has_qdd) log.qdd = block(map.qdd, map.qdd_scale, map.qdd_linear_scale);
  check_log_time(log.t, path);
  return log;
}

}  // namespace dyncal::host
