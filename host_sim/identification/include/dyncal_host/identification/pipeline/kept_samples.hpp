#pragma once
// Which samples of a log identification keeps after filtering, and keeping them in place.

#include <Eigen/Core>
#include <utility>
#include <vector>

namespace dyncal::host {

/// The samples a prepared log keeps (Gautier's decimation): every `step`-th sample of each
/// segment's interior, `edge` samples dropped at both ends of every segment (there filtering and
/// differentiation are one-sided). A segment not longer than 2 edge keeps none. Rows are the log's
/// (0-based); segments are [first, end) rows in order.
struct KeptSamples {
  std::vector<std::pair<Eigen::Index, Eigen::Index>> segments;
  Eigen::Index edge = 0;
  Eigen::Index step = 1;

  /// Samples kept of the segment [a, b).
  Eigen::Index count(Eigen::Index a, Eigen::Index b) const {
    const Eigen::Index len = b - a;
    return len <= 2 * edge ? 0 : (len - 2 * edge + step - 1) / step;
  }
  /// Samples kept of the whole log.
  Eigen::Index count() const {
    Eigen::Index n = 0;
    for (const auto& [a, b] : segments) n += count(a, b);
    return n;
  }
  /// Calls f(row, k) for every kept row of the log in order, k its index among the kept samples.
  template <class F>
  void for_each(F f) const {
    Eigen::Index k = 0;
    for (const auto& [a, b] : segments) {
      const Eigen::Index n = count(a, b);
      for (Eigen::Index i = 0; i < n; ++i) f(a + edge + i * step, k++);
    }
  }
};

/// Shrinks `m` (a log's signal: one row per sample, columns joints) to its kept rows, in order, in
/// its own buffer: the rows move forward column by column (no kept value is overwritten before it
/// is read: a row's new place never lies after its old one) and the buffer is shortened by
/// realloc, so no second copy of the signal is ever allocated (docs/reliability.md, memory of
/// identification). m must have as many rows as the log `kept` describes.
void keep_rows_in_place(Eigen::MatrixXd& m, const KeptSamples& kept);

/// As above for one signal (time stamps).
void keep_rows_in_place(Eigen::VectorXd& v, const KeptSamples& kept);

}  // namespace dyncal::host
