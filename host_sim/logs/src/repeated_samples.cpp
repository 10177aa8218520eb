// Stale rows of a logger that re-writes its last reading (repeated_samples.hpp).
#include "dyncal_host/logs/repeated_samples.hpp"

#include <cmath>
#include <limits>
#include <vector>

namespace dyncal::host {
namespace {

using Eigen::Index;

bool same_row(const JointLog& log, Index a, Index b) {
  auto same = [&](const Eigen::MatrixXd& m) { return m.size() == 0 || (m.row(a).array() == m.row(b).array()).all(); };
  return same(log.q) && same(log.tau) && (!log.has_qd || same(log.qd)) && (!log.has_qdd || same(log.qdd));
}

}  // namespace

Eigen::VectorXd position_quanta(const JointLog& log) {
  const int n = log.joints();
  Eigen::VectorXd quantum = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::infinity());
  for (const auto& [a, b] : log.segments())
    for (Index k = a + 1; k < b; ++k)
      for (int j = 0; j < n; ++j) {
        const double step = std::abs(log.q(k, j) - log.q(k - 1, j));
        if (step > 0 && step < quantum[j]) quantum[j] = step;
      }
  for (int j = 0; j < n; ++j)
    if (!std::isfinite(quantum[j])) quantum[j] = 0;
  return quantum;
}

RepeatedSamples drop_repeated_samples(JointLog& log) {
  RepeatedSamples r;
  const Index S = log.samples();
  const int n = log.joints();
  const Eigen::VectorXd quantum = position_quanta(log);
  std::vector<char> keep(static_cast<size_t>(S), 1);
  for (const auto& [a, b] : log.segments()) {
    for (Index first = a + 1; first < b;) {
      if (!same_row(log, first, first - 1)) {
        ++first;
        continue;
      }
      Index end = first + 1;  // the run: rows [first, end), each identical to row first - 1
      while (end < b && same_row(log, end, first - 1)) ++end;
      const long rows = static_cast<long>(end - first);
      bool moved = false;
      if (end < b)
        for (int j = 0; j < n && !moved; ++j)
          moved = quantum[j] > 0 && std::abs(log.q(end, j) - log.q(first - 1, j)) >= 2 * quantum[j];
      if (moved) {
        for (Index k = first; k < end; ++k) keep[static_cast<size_t>(k)] = 0;
        r.dropped += rows;
        ++r.runs;
        if (rows > r.longest) {
          r.longest = rows;
          r.longest_at = log.t[first];
        }
      } else {
        r.kept_at_rest += rows;
      }
      first = end;
    }
  }
  if (r.dropped == 0) return r;
  JointLog out = sized_like(log, S - r.dropped);
  Index row = 0;
  for (const auto& [a, b] : log.segments()) {
    if (row > 0) out.segment_starts.push_back(row);
    for (Index k = a; k < b; ++k) {
      if (!keep[static_cast<size_t>(k)]) continue;
      out.t[row] = log.t[k];
      out.q.row(row) = log.q.row(k);
      out.tau.row(row) = log.tau.row(k);
      if (log.has_qd) out.qd.row(row) = log.qd.row(k);
      if (log.has_qdd) out.qdd.row(row) = log.qdd.row(k);
      ++row;
    }
  }
  log = std::move(out);
  return r;
}

}  // namespace dyncal::host
