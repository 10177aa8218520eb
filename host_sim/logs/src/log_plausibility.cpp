#include "dyncal_host/logs/log_plausibility.hpp"

#include <cmath>
#include <cstdio>
#include <type_traits>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/number_text.hpp"

namespace dyncal::host {
namespace {

template <class Matrix>
struct Column {
  Matrix* m;
  const char* name;
};

// The log's measured blocks (q, qd and qdd when measured, tau); Log is JointLog or const JointLog.
template <class Log>
auto columns(Log& log) {
  using Matrix = std::remove_reference_t<decltype((log.q))>;  // const for a const log
  std::vector<Column<Matrix>> c{{&log.q, "q"}};
  if (log.has_qd) c.push_back({&log.qd, "qd"});
  if (log.has_qdd) c.push_back({&log.qdd, "qdd"});
  c.push_back({&log.tau, "tau"});
  return c;
}

// [lo, hi] of column `name` of joint j, and the bound in words.
void bounds(const RobotDescription& r, const std::string& name, int j, double* lo, double* hi, std::string* words) {
  if (name == "q") {
    const double margin = kPositionMargin * (r.q_max[j] - r.q_min[j]);
    *lo = r.q_min[j] - margin;
    *hi = r.q_max[j] + margin;
    *words = "[q_min, q_max] = [" + number_text(r.q_min[j], 6) + ", " + number_text(r.q_max[j], 6) +
             "] rad widened by " + number_text(100 * kPositionMargin, 6) + " % of the range";
    return;
  }
  const double rating = name == "qd" ? r.qd_max[j] : name == "qdd" ? r.qdd_max[j] : r.tau_max[j];
  *hi = kRatingMultiple * rating;
  *lo = -*hi;
  const std::string what = name == "qd" ? "qd_max" : name == "qdd" ? "qdd_max" : "tau_max";
  *words = number_text(kRatingMultiple, 6) + " x " + what + " = " + number_text(*hi, 6) +
           (name == "qd"    ? " rad/s"
            : name == "qdd" ? " rad/s^2"
                            : " Nm");
}

}  // namespace

std::vector<ImplausibleValue> find_implausible(const JointLog& log, const RobotDescription& robot) {
  std::vector<ImplausibleValue> out;
  const auto cols = columns(log);
  for (Eigen::Index s = 0; s < log.samples(); ++s) {
    for (const auto& c : cols) {
      for (int j = 0; j < log.joints(); ++j) {
        double lo = 0, hi = 0;
        std::string words;
        bounds(robot, c.name, j, &lo, &hi, &words);
        const double v = (*c.m)(s, j);
        if (v >= lo && v <= hi) continue;
        out.push_back({static_cast<long>(s + 1), c.name + std::to_string(j + 1), v, words});
      }
    }
  }
  return out;
}

std::vector<std::string> check_plausibility(JointLog& log, const RobotDescription& robot, bool drop) {
  const auto bad = find_implausible(log, robot);
  std::vector<std::string> lines;
  if (bad.empty()) return lines;
  auto describe = [&](const ImplausibleValue& b) {
    return b.column + " = " + number_text(b.value, 6) + " at data row " + std::to_string(b.row) + " (outside " +
           b.bound + ")";
  };
  if (!drop) {
    throw InputError(log.source + ": implausible value " + describe(bad.front()) + "; " + std::to_string(bad.size()) +
                     " such value" + (bad.size() == 1 ? "" : "s") +
                     " in the log (docs/cli.md: fix the log or pass --drop-outliers)");
  }
  // Mark, then interpolate each marked value from the nearest unmarked ones in its column.
  for (const auto& c : columns(log)) {
    for (int j = 0; j < log.joints(); ++j) {
      const std::string name = c.name + std::to_string(j + 1);
      std::vector<char> marked(static_cast<size_t>(log.samples()), 0);
      bool any = false;
      for (const auto& b : bad) {
        if (b.column == name) marked[static_cast<size_t>(b.row - 1)] = 1, any = true;
      }
      if (!any) continue;
      Eigen::Index prev = -1;
      auto& m = *c.m;
      const Eigen::Index S = log.samples();
      for (Eigen::Index s = 0; s < S; ++s) {
        if (!marked[static_cast<size_t>(s)]) {
          prev = s;
          continue;
        }
        Eigen::Index next = s + 1;
        while (next < S && marked[static_cast<size_t>(next)]) ++next;
        if (prev < 0 && next >= S) throw InputError(log.source + ": column " + name + " has no plausible value");
        if (prev < 0) {
          m(s, j) = m(next, j);
        } else if (next >= S) {
          m(s, j) = m(prev, j);
        } else {
          const double w = static_cast<double>(s - prev) / static_cast<double>(next - prev);
          m(s, j) = (1 - w) * m(prev, j) + w * m(next, j);
        }
      }
    }
  }
  for (const auto& b : bad) lines.push_back("dropped " + describe(b) + ", interpolated from its neighbours");
  return lines;
}

}  // namespace dyncal::host
