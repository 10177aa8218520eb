#include "dyncal_host/logs/sample_clock.hpp"

#include <algorithm>
#include <cmath>

namespace dyncal::host {

double median_step(const Eigen::VectorXd& t, const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments) {
  std::vector<double> steps;
  steps.reserve(static_cast<size_t>(t.size()));
  for (const auto& [a, b] : segments) {
    for (Eigen::Index i = a + 1; i < b; ++i) steps.push_back(t[i] - t[i - 1]);
  }
  if (steps.empty()) return 0.0;
  auto mid = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
  std::nth_element(steps.begin(), mid, steps.end());
  return *mid;
}

SampleClock estimate_sample_clock(const Eigen::VectorXd& t,
                                  const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments, double period) {
  SampleClock c;
  c.t = t;
  c.period = period;
  double sum_e2 = 0, periods = 0, spanned = 0;
  long n_samples = 0;
  for (const auto& [a, b] : segments) {
    const Eigen::Index m = b - a;
    if (m < 2) continue;
    Eigen::VectorXd n(m);
    double offset = t[a], T = period;
    for (int pass = 0; pass < 3; ++pass) {
      n[0] = 0;
      for (Eigen::Index i = 1; i < m; ++i) {
        // Ticks from the previous sample's clock time (pass 0: its stamp): jitter does not accumulate.
        const double previous = pass == 0 ? t[a + i - 1] : offset + T * n[i - 1];
        n[i] = n[i - 1] + std::max(1.0, std::round((t[a + i] - previous) / T));
      }
      // Least squares t = offset + T n.
      const double nm = n.mean(), tm = t.segment(a, m).mean();
      const double snn = (n.array() - nm).square().sum();
      if (!(snn > 0)) break;
      T = ((n.array() - nm) * (t.segment(a, m).array() - tm)).sum() / snn;
      offset = tm - T * nm;
    }
    c.t.segment(a, m) = offset + T * n.array();
    sum_e2 += (t.segment(a, m) - c.t.segment(a, m)).squaredNorm();
    n_samples += static_cast<long>(m);
    spanned += T * n[m - 1];
    periods += n[m - 1];
    c.missing += static_cast<long>(n[m - 1]) + 1 - static_cast<long>(m);
  }
  if (periods > 0) c.period = spanned / periods;
  c.stamp_jitter = n_samples > 0 ? std::sqrt(sum_e2 / static_cast<double>(n_samples)) / c.period : 0.0;
  return c;
}

Eigen::VectorXd third_difference_power(const Eigen::MatrixXd& x,
                                       const std::vector<std::pair<Eigen::Index, Eigen::Index>>& pieces) {
  Eigen::VectorXd power = Eigen::VectorXd::Zero(x.cols());
  double count = 0;
  for (const auto& [a, b] : pieces) {
    for (Eigen::Index i = a + 3; i < b; ++i) {
      power += (x.row(i) - 3.0 * x.row(i - 1) + 3.0 * x.row(i - 2) - x.row(i - 3)).transpose().cwiseAbs2();
      count += 1;
    }
  }
  return count > 0 ? Eigen::VectorXd(power / count) : power;
}

}  // namespace dyncal::host
