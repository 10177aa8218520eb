#pragma once
// Least-squares fit of one harmonic of a joint angle to a residual (private to host_sim/diagnosis).

#include <Eigen/Core>
#include <cmath>
#include <optional>

namespace dyncal::host::detail {

/// RSS reduction of the least-squares fit of a sin(k q_j) + b cos(k q_j) to residual(s) over the
/// samples of `q` (S x N); nullopt when sin and cos are collinear on the data.
template <class Residual>
std::optional<double> harmonic_rss_reduction(const Eigen::MatrixXd& q, int j, int k, Residual residual) {
  double ss = 0, cc = 0, sc = 0, sr = 0, cr = 0;
  for (Eigen::Index s = 0; s < q.rows(); ++s) {
    const double a = std::sin(k * q(s, j)), b = std::cos(k * q(s, j)), r = residual(s);
    ss += a * a;
    cc += b * b;
    sc += a * b;
    sr += a * r;
    cr += b * r;
  }
  const double det = ss * cc - sc * sc;
  if (det <= 1e-12 * ss * cc) return std::nullopt;
  return (cc * sr * sr - 2 * sc * sr * cr + ss * cr * cr) / det;
}

}  // namespace dyncal::host::detail
