#pragma once

#include <Eigen/Core>

namespace dyncal::host {

/// Central differences of each column of x (rows = samples, uniform period dt [s]):
/// (x[i+1] - x[i-1]) / (2 dt) inside, one-sided first differences at both ends.
Eigen::MatrixXd central_difference(const Eigen::MatrixXd& x, double dt);

/// Effective number of independent samples of a residual series r (S values): S / (1 + 2 sum rho_k),
/// rho_k its autocorrelation at lag k, summed over the initial positive sequence (Geyer 1992), lags
/// below S / 4. A low-passed residual carrying smooth model error has far fewer than S.
double effective_samples(const Eigen::VectorXd& r);

}  // namespace dyncal::host
