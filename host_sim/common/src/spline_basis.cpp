#include "dyncal_host/common/spline_basis.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>

#include "dyncal_host/common/jackknife.hpp"

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

namespace {

/// The full B-spline coefficients (knots.size() - 4) of a shape's coefficients (shape_basis_columns
/// of them): a = M c. Without the first basis function M = [0; I]; without_linear, M = Z, the
/// coefficient vectors orthogonal to the constant's and x's (all 1, and the Greville abscissae).
Eigen::MatrixXd coefficient_map(const std::vector<double>& knots, bool without_linear) {
  const Eigen::Index m = static_cast<Eigen::Index>(knots.size()) - 4;
  if (!without_linear) {
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(m, m - 1);
    M.bottomRows(m - 1).setIdentity();
    return M;
  }
  Eigen::MatrixXd A(m, 2);
  for (Eigen::Index k = 0; k < m; ++k) {
    A(k, 0) = 1.0;
    A(k, 1) =
        (knots[static_cast<size_t>(k + 1)] + knots[static_cast<size_t>(k + 2)] + knots[static_cast<size_t>(k + 3)]) /
        3.0;  // Greville abscissa: x = sum_k of it B_k
  }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(A);
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(m, m);
  return Q.rightCols(m - 2);
}

}  // namespace

Eigen::MatrixXd shape_basis(const Eigen::Ref<const Eigen::VectorXd>& x, const std::vector<double>& knots,
                            bool without_linear) {
  const Eigen::Index m = static_cast<Eigen::Index>(knots.size()) - 4;
  if (shape_basis_columns(knots, without_linear) == 0) return Eigen::MatrixXd(x.size(), 0);
  const Eigen::MatrixXd B = spline_basis(x, knots);
  if (!without_linear) return B.rightCols(m - 1);
  return B * coefficient_map(knots, true);
}

Eigen::MatrixXd shape_roughness_rows(const std::vector<double>& knots, bool without_linear) {
  const int cols = shape_basis_columns(knots, without_linear);
  if (cols == 0) return Eigen::MatrixXd(0, 0);
  const std::vector<double>& t = knots;
  const Eigen::Index n = static_cast<Eigen::Index>(t.size()) - 4;  // cubic basis functions
  // f'' of f = sum_i a_i B_i (cubic) is sum_i a''_i L_i, L_i the linear B-spline on [t_i, t_i+2]
  // (its peak at t_i+1): a'_i = 3 (a_i - a_i-1) / (t_i+3 - t_i), i = 1..n-1, then
  // a''_i = 2 (a'_i - a'_i-1) / (t_i+2 - t_i), i = 2..n-1 (de Boor's derivative of a B-spline).
  Eigen::MatrixXd D1 = Eigen::MatrixXd::Zero(n - 1, n), D2 = Eigen::MatrixXd::Zero(n - 2, n - 1);
  for (Eigen::Index i = 1; i < n; ++i) {
    const double h = t[static_cast<size_t>(i + 3)] - t[static_cast<size_t>(i)];
    D1(i - 1, i) = 3.0 / h;
    D1(i - 1, i - 1) = -3.0 / h;
  }
  for (Eigen::Index i = 2; i < n; ++i) {
    const double h = t[static_cast<size_t>(i + 2)] - t[static_cast<size_t>(i)];
    D2(i - 2, i - 1) = 2.0 / h;
    D2(i - 2, i - 2) = -2.0 / h;
  }
  // a''_i is f'' at the distinct knot t_i+1 (i = 2..n-1: lo, the interior knots, hi); f'' is linear
  // between them, so two Gauss-Legendre points per interval integrate (f'')^2 exactly.
  const Eigen::MatrixXd second = D2 * D1 * coefficient_map(knots, without_linear);  // (n - 2) x cols
  const Eigen::Index intervals = n - 3;
  Eigen::MatrixXd L(2 * intervals, cols);
  const double s[2] = {0.5 - 0.5 / std::sqrt(3.0), 0.5 + 0.5 / std::sqrt(3.0)};
  for (Eigen::Index k = 0; k < intervals; ++k) {
    const double h = t[static_cast<size_t>(k + 4)] - t[static_cast<size_t>(k + 3)];
    for (int g = 0; g < 2; ++g)
      L.row(2 * k + g) = std::sqrt(0.5 * h) * ((1.0 - s[g]) * second.row(k) + s[g] * second.row(k + 1));
  }
  return L;
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

void shape_band(const std::vector<double>& knots, bool without_linear,
                const std::vector<std::vector<double>>& fold_coefficients, const std::vector<double>& y,
                std::vector<double>& lo, std::vector<double>& hi) {
  const size_t K = fold_coefficients.size(), P = y.size();
  lo = hi = y;
  if (K < 2) return;
  std::vector<std::vector<double>> curves(K);
  for (size_t k = 0; k < K; ++k) {
    std::vector<double> x;
    shape_curve(knots, fold_coefficients[k], without_linear, static_cast<int>(P), x, curves[k]);
    if (curves[k].size() != P) return;
  }
  for (size_t p = 0; p < P; ++p) {
    const double half = jackknife_half_width(K, [&](size_t k) { return curves[k][p]; });
    lo[p] = y[p] - half;
    hi[p] = y[p] + half;
  }
}

}  // namespace dyncal::host
