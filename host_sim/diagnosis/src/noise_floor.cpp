#include "noise_floor.hpp"

#include <algorithm>
#include <cmath>

#include "dyncal_host/identification/methods/butterworth.hpp"

namespace dyncal::host::detail {
namespace {

/// rho(0) and rho(lag) of filtfilt's impulse response at the raw rate (1 and 0 without a filter).
std::pair<double, double> filter_autocorrelation(const IdentifyOptions& io, double raw_rate_hz, Eigen::Index lag) {
  if (!(io.cutoff_hz < 0.5 * raw_rate_hz)) return {1.0, 0.0};
  const ButterworthLowPass filter(io.filter_order, io.cutoff_hz, raw_rate_hz);
  // An impulse in the middle of a run long enough for the response to die out at both ends.
  const Eigen::Index n =
      std::max<Eigen::Index>(512 + 2 * lag, static_cast<Eigen::Index>(std::ceil(80 * raw_rate_hz / io.cutoff_hz)));
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(n, 1);
  h(n / 2, 0) = 1.0;
  filter.filtfilt(h);
  const Eigen::VectorXd x = h.col(0);
  return {x.squaredNorm(), x.head(n - lag).dot(x.tail(n - lag))};
}

}  // namespace

Eigen::VectorXd noise_floor_per_row(const StackedData& d, const Eigen::VectorXd& residual,
                                    const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments,
                                    const IdentifyOptions& io, double raw_rate_hz) {
  const int N = static_cast<int>(d.q.cols());
  const Eigen::Index lag = std::max<Eigen::Index>(1, std::lround(raw_rate_hz / d.rate_hz));
  const auto [rho0, rho_lag] = filter_autocorrelation(io, raw_rate_hz, lag);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(N);
  for (int j = 0; j < N; ++j) {
    std::vector<double> d2;
    for (const auto& [a, b] : segments)
      for (Eigen::Index s = a + 1; s < b; ++s) {
        const Eigen::Index r0 = (s - 1) * N + j, r1 = s * N + j;
        if (!d.fit_row[r0] || !d.fit_row[r1]) continue;
        const double v = residual[r1] - residual[r0];
        d2.push_back(v * v);
      }
    if (d2.empty()) continue;
    auto mid = d2.begin() + static_cast<std::ptrdiff_t>(d2.size() / 2);
    std::nth_element(d2.begin(), mid, d2.end());
    const double sigma2 = *mid / 0.4549364 / std::max(1e-300, 2 * (rho0 - rho_lag));
    out[j] = rho0 * sigma2;
  }
  return out;
}

}  // namespace dyncal::host::detail
