#include "dyncal_host/common/spline_basis.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>

namespace dyncal::host {

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

Eigen::MatrixXd shape_basis(const Eigen::Ref<const Eigen::VectorXd>& x, const std::vector<double>& knots,
                            bool without_linear) {
  const Eigen::Index m = static_cast<Eigen::Index>(knots.size()) - 4;
  if (shape_basis_columns(knots, without_linear) == 0) return Eigen::MatrixXd(x.size(), 0);
  const Eigen::MatrixXd B = spline_basis(x, knots);
  if (!without_linear) return B.rightCols(m - 1);
  Eigen::MatrixXd M(m, 2);
  for (Eigen::Index k = 0; k < m; ++k) {
    M(k, 0) = 1.0;
    M(k, 1) =
        (knots[static_cast<size_t>(k + 1)] + knots[static_cast<size_t>(k + 2)] + knots[static_cast<size_t>(k + 3)]) /
        3.0;  // Greville abscissa: x = sum_k of it B_k
  }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(M);
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(m, m);
  return B * Q.rightCols(m - 2);
}

void shape_curve(const std::vector<double>& knots, const std::vector<double>& coefficients, bool without_linear,
                 int points, std::vector<double>& x, std::vector<double>& y) {
  x.clear(), y.clear();
  const int m = shape_basis_columns(knots, without_linear);
  if (m == 0 || static_cast<int>(coefficients.size()) != m || points < 2) return;
  Eigen::VectorXd at(points);
  for (Eigen::Index k = 0; k < at.size(); ++k)
    at[k] = knots.front() + (knots.back() - knots.front()) * static_cast<double>(k) / static_cast<double>(points - 1);
  Eigen::VectorXd torque =
      shape_basis(at, knots, without_linear) * Eigen::Map<const Eigen::VectorXd>(coefficients.data(), m);
  torque.array() -= torque.mean();  // centred: its level trades with the model's other columns
  x.assign(at.data(), at.data() + at.size());
  y.assign(torque.data(), torque.data() + torque.size());
}

}  // namespace dyncal::host
