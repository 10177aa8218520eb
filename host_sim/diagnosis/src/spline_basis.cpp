#include "spline_basis.hpp"

#include <algorithm>
#include <cmath>

namespace dyncal::host::detail {

std::vector<double> spline_knots(const Eigen::Ref<const Eigen::VectorXd>& x, int interior) {
  if (x.size() < 2) return {};
  std::vector<double> sorted(x.data(), x.data() + x.size());
  std::sort(sorted.begin(), sorted.end());
  const double lo = sorted.front(), hi = sorted.back();
  if (!(hi > lo)) return {};
  std::vector<double> inner;
  for (int k = 1; k <= interior; ++k) {
    const double v = sorted[static_cast<size_t>(
        std::lround(static_cast<double>(k) / (interior + 1) * static_cast<double>(sorted.size() - 1)))];
    // a knot at least 1e-6 of the span from its neighbours and the ends (a variable resting at one
    // value puts several quantiles there)
    const double gap = 1e-6 * (hi - lo);
    if (v - lo > gap && hi - v > gap && (inner.empty() || v - inner.back() > gap)) inner.push_back(v);
  }
  std::vector<double> knots(4, lo);
  knots.insert(knots.end(), inner.begin(), inner.end());
  knots.insert(knots.end(), 4, hi);
  return knots;
}

Eigen::MatrixXd spline_basis(const Eigen::Ref<const Eigen::VectorXd>& x, const std::vector<double>& knots) {
  const int m = static_cast<int>(knots.size()) - 4;  // basis functions
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(x.size(), std::max(m, 0));
  if (m <= 0) return B;
  const double lo = knots.front(), hi = knots.back();
  for (Eigen::Index r = 0; r < x.size(); ++r) {
    const double v = std::clamp(x[r], lo, hi);
    // the span [knots[i], knots[i + 1]) holding v (the last non-empty one at v = hi)
    int i = static_cast<int>(std::upper_bound(knots.begin(), knots.end(), v) - knots.begin()) - 1;
    i = std::clamp(i, 3, m - 1);
    // de Boor's recurrence for the four non-zero cubic basis functions N_{i-3..i}
    double N[4] = {1, 0, 0, 0}, left[4], right[4];
    for (int d = 1; d <= 3; ++d) {
      left[d] = v - knots[static_cast<size_t>(i + 1 - d)];
      right[d] = knots[static_cast<size_t>(i + d)] - v;
      double saved = 0;
      for (int k = 0; k < d; ++k) {
        const double den = right[k + 1] + left[d - k];
        const double tmp = den > 0 ? N[k] / den : 0.0;
        N[k] = saved + right[k + 1] * tmp;
        saved = left[d - k] * tmp;
      }
      N[d] = saved;
    }
    for (int k = 0; k < 4; ++k) B(r, i - 3 + k) = N[k];
  }
  return B;
}

}  // namespace dyncal::host::detail
