#pragma once

#include <Eigen/Core>
#include <utility>
#include <vector>

namespace dyncal::host {

/// Central differences of each column of x (rows = samples, uniform period dt [s]):
/// (x[i+1] - x[i-1]) / (2 dt) inside, one-sided first differences at both ends.
Eigen::MatrixXd central_difference(const Eigen::Ref<const Eigen::MatrixXd>& x, double dt);

/// Derivative of a low-passed signal (rows = samples, period dt [s]): the five-point central
/// difference (x[i-2] - 8 x[i-1] + 8 x[i+1] - x[i+2]) / (12 dt) inside, central_difference's
/// stencils at the two samples next to each end. Its gain at frequency f is
/// (8 sin w - sin 2w) / (6 w), w = 2 pi f dt: 0.998 at a 20 Hz cut-off sampled at 250 Hz, where the
/// three-point difference has 0.959 (0.92 for qdd, twice), which would leave the regressor's
/// inertial columns short of tau's at every start and stop of a logged motion.
Eigen::MatrixXd smooth_derivative(const Eigen::Ref<const Eigen::MatrixXd>& x, double dt);

/// Standard deviation of the white noise on a sampled signal x (rows = samples of one segment each
/// in `segments`, [first, end) rows): the median absolute fourth difference over all segments,
/// MAD(D^4 x) / (0.6745 sqrt(70)) (D^4 of white noise has variance 70 sigma^2; a smooth signal's
/// fourth difference is O(h^4) and the median ignores the few steps where motion dominates),
/// floored at the resolution the data carry: a quantised signal's smallest nonzero step / sqrt(12),
/// and the double rounding of its largest value. Per column.
Eigen::VectorXd white_noise_std(const Eigen::MatrixXd& x,
                                const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments);

/// The two-sided normal quantile of the standstill test: a joint at rest (true velocity 0, Gaussian
/// velocity noise sigma_v) reads |qd| > kStandstillQuantile sigma_v on 0.1 % of its samples.
inline constexpr double kStandstillQuantile = 3.29;

/// Effective number of independent samples of a residual series r (S values): S / (1 + 2 sum rho_k),
/// rho_k its autocorrelation at lag k, summed over the initial positive sequence (Geyer 1992), lags
/// below S / 4. A low-passed residual carrying smooth model error has far fewer than S.
double effective_samples(const Eigen::Ref<const Eigen::VectorXd>& r);

}  // namespace dyncal::host
