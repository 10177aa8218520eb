#include "dyncal_host/identification/methods/signal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dyncal::host {

Eigen::MatrixXd central_difference(const Eigen::Ref<const Eigen::MatrixXd>& x, double dt) {
  const Eigen::Index n = x.rows();
  Eigen::MatrixXd d(n, x.cols());
  if (n < 2) {
    d.setZero();
    return d;
  }
  d.row(0) = (x.row(1) - x.row(0)) / dt;
  d.row(n - 1) = (x.row(n - 1) - x.row(n - 2)) / dt;
  if (n > 2) d.middleRows(1, n - 2) = (x.bottomRows(n - 2) - x.topRows(n - 2)) / (2.0 * dt);
  return d;
}

Eigen::MatrixXd smooth_derivative(const Eigen::Ref<const Eigen::MatrixXd>& x, double dt) {
  const Eigen::Index n = x.rows();
  Eigen::MatrixXd d = central_difference(x, dt);
  if (n > 4)
    d.middleRows(2, n - 4) =
        (x.topRows(n - 4) - 8.0 * x.middleRows(1, n - 4) + 8.0 * x.middleRows(3, n - 4) - x.bottomRows(n - 4)) /
        (12.0 * dt);
  return d;
}

Eigen::VectorXd white_noise_std(const Eigen::MatrixXd& x,
                                const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments) {
  Eigen::VectorXd out(x.cols());
  std::vector<double> d4;
  for (Eigen::Index c = 0; c < x.cols(); ++c) {
    d4.clear();
    double smallest_step = std::numeric_limits<double>::infinity(), largest = 0;
    for (const auto& [a, b] : segments) {
      for (Eigen::Index i = a; i < b; ++i) {
        largest = std::max(largest, std::abs(x(i, c)));
        if (i > a) {
          const double step = std::abs(x(i, c) - x(i - 1, c));
          if (step > 0) smallest_step = std::min(smallest_step, step);
        }
        if (i >= a + 4)
          d4.push_back(std::abs(x(i, c) - 4 * x(i - 1, c) + 6 * x(i - 2, c) - 4 * x(i - 3, c) + x(i - 4, c)));
      }
    }
    double mad = 0;
    if (!d4.empty()) {
      auto mid = d4.begin() + static_cast<std::ptrdiff_t>(d4.size() / 2);
      std::nth_element(d4.begin(), mid, d4.end());
      mad = *mid;
    }
    double sigma = mad / (0.6745 * std::sqrt(70.0));
    // A quantised signal: steps are multiples of its resolution. Only a floor when the smallest
    // step is a plausible resolution, i.e. not below the double rounding.
    const double rounding = std::numeric_limits<double>::epsilon() * std::max(largest, 1e-300);
    if (std::isfinite(smallest_step)) sigma = std::max(sigma, smallest_step / std::sqrt(12.0));
    out[c] = std::max(sigma, rounding);
  }
  return out;
}

double effective_samples(const Eigen::Ref<const Eigen::VectorXd>& r) {
  const Eigen::Index S = r.size();
  const Eigen::VectorXd c = r.array() - r.mean();
  const double c0 = c.squaredNorm();
  double tau = 1.0;
  for (Eigen::Index k = 1; k < S / 4 && c0 > 0; ++k) {
    const double rho = c.head(S - k).dot(c.tail(S - k)) / c0;
    if (rho <= 0) break;
    tau += 2.0 * rho;
  }
  return static_cast<double>(S) / tau;
}

}  // namespace dyncal::host
