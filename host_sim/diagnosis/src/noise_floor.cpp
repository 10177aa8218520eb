#include "noise_floor.hpp"

#include <algorithm>
#include <cmath>

#include "dyncal_host/common/jackknife.hpp"
#include "dyncal_host/common/normal_quantile.hpp"
#include "dyncal_host/identification/methods/butterworth.hpp"
#include "dyncal_host/identification/methods/signal.hpp"

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
                                    const IdentifyOptions& io, double raw_rate_hz, Eigen::VectorXd* lo,
                                    Eigen::VectorXd* hi) {
  const int N = static_cast<int>(d.q.cols());
  const Eigen::Index lag = std::max<Eigen::Index>(1, std::lround(raw_rate_hz / d.rate_hz));
  const std::pair<double, double> rho = filter_autocorrelation(io, raw_rate_hz, lag);
  const double rho0 = rho.first, rho_lag = rho.second;
  auto floor_of = [&](double d2) {  // the median of d^2 -> the floor
    return rho0 * (d2 / 0.4549364 / std::max(1e-300, 2 * (rho0 - rho_lag)));
  };
  Eigen::VectorXd out = Eigen::VectorXd::Zero(N);
  if (lo) *lo = Eigen::VectorXd::Zero(N);
  if (hi) *hi = Eigen::VectorXd::Zero(N);
  for (int j = 0; j < N; ++j) {
    std::vector<double> diff;
    for (const auto& [a, b] : segments)
      for (Eigen::Index s = a + 1; s < b; ++s) {
        const Eigen::Index r0 = (s - 1) * N + j, r1 = s * N + j;
        if (!d.fit_row[r0] || !d.fit_row[r1]) continue;
        diff.push_back(residual[r1] - residual[r0]);
      }
    if (diff.empty()) continue;
    std::vector<double> d2(diff.size());
    std::transform(diff.begin(), diff.end(), d2.begin(), [](double v) { return v * v; });
    // The k-th order statistic of d2 (partially sorting it); the median's k is size / 2.
    auto order = [&d2](size_t k) {
      std::nth_element(d2.begin(), d2.begin() + static_cast<std::ptrdiff_t>(k), d2.end());
      return d2[k];
    };
    auto at = [&](double p) {
      return order(static_cast<size_t>(std::lround(std::clamp(p, 0.0, 1.0) * static_cast<double>(d2.size() - 1))));
    };
    out[j] = floor_of(order(d2.size() / 2));
    if (!lo && !hi) continue;
    const double n_eff = std::max(
        1.0, effective_samples(Eigen::Map<const Eigen::VectorXd>(diff.data(), static_cast<Eigen::Index>(diff.size()))));
    const double half = kZ95 * std::sqrt(0.25 / n_eff);
    if (lo) (*lo)[j] = floor_of(at(0.5 - half));
    if (hi) (*hi)[j] = floor_of(at(0.5 + half));
  }
  return out;
}

Eigen::VectorXd NoiseFloor::rss(const Eigen::VectorXd& per, int without) const {
  Eigen::VectorXd n = rows.colwise().sum().transpose();
  if (without >= 0) n -= rows.row(without).transpose();
  return per.cwiseProduct(n);
}

NoiseFloor noise_floor(const StackedData& d, const Eigen::VectorXd& residual,
                       const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments, const IdentifyOptions& io,
                       double raw_rate_hz, const std::vector<int>& fold, int folds) {
  const int N = static_cast<int>(d.q.cols());
  NoiseFloor f;
  f.per_row = noise_floor_per_row(d, residual, segments, io, raw_rate_hz, &f.per_row_lo, &f.per_row_hi);
  f.rows = Eigen::MatrixXd::Zero(folds, N);
  for (Eigen::Index r = 0; r < d.y.size(); ++r) {
    const int k = fold[static_cast<size_t>(r / N)];
    if (d.fit_row[r] && k >= 0 && k < folds) f.rows(k, r % N) += 1;
  }
  return f;
}

double excess_share(const std::vector<int>& joints, const Eigen::VectorXd& before, const Eigen::VectorXd& after,
                    const Eigen::VectorXd& floor) {
  double drop = 0, excess = 0;
  for (int j : joints) {
    drop += before[j] - after[j];
    excess += std::max(0.0, before[j] - floor[j]);
  }
  return excess > 0 ? std::clamp(drop / excess, 0.0, 1.0) : 0.0;
}

std::pair<double, double> excess_share_interval(const std::vector<int>& joints, const Eigen::MatrixXd& before_folds,
                                                const Eigen::MatrixXd& after_folds, const NoiseFloor& floor) {
  const Eigen::VectorXd before = before_folds.colwise().sum().transpose(),
                        after = after_folds.colwise().sum().transpose();
  const double at_lo = excess_share(joints, before, after, floor.rss(floor.per_row_lo));
  const double at_hi = excess_share(joints, before, after, floor.rss(floor.per_row_hi));
  const double share = excess_share(joints, before, after, floor.rss(floor.per_row));
  const auto K = static_cast<size_t>(before_folds.rows());
  double half = 0;
  if (K >= 2 && after_folds.rows() == before_folds.rows())
    half = jackknife_half_width(K, [&](size_t k) {
      const auto f = static_cast<Eigen::Index>(k);
      return excess_share(joints, before - before_folds.row(f).transpose(), after - after_folds.row(f).transpose(),
                          floor.rss(floor.per_row, static_cast<int>(k)));
    });
  return {std::clamp(std::min({at_lo, at_hi, share}) - half, 0.0, 1.0),
          std::clamp(std::max({at_lo, at_hi, share}) + half, 0.0, 1.0)};
}

}  // namespace dyncal::host::detail
