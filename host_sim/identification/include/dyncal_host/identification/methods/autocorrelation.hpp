#pragma once
// The residual's autocorrelation and the parameters' variance: the factor every batch fit inflates
// its white-noise covariance by.

#include <Eigen/Core>
#include <vector>

#include "dyncal_host/model/stacked_data.hpp"

namespace dyncal::host {

/// The residuals of filtered, decimated data are autocorrelated, so the white-noise covariance
/// (sigma^2 (W^T W)^-1, or a filter's P) understates the parameters' variance: the factor S / n_eff
/// to inflate it by, n_eff the residual's effective samples (signal.hpp: effective_samples, Geyer
/// 1992) per joint over the rows with train[s] and fit_row, the row-weighted mean over the joints, at
/// least 1. residual: (S N) stacked, y - W phi.
double autocorrelation_inflation(const StackedData& d, const std::vector<char>& train, const Eigen::VectorXd& residual);

/// autocorrelation_inflation of the residual y - W phi (phi: P), computed joint by joint from the
/// regressor's rows instead of stored: N passes over the samples, no (S N) vector (the streamed fit's
/// memory, docs/reliability.md). The same figure, bit for bit.
double streamed_autocorrelation_inflation(const StackedData& d, const std::vector<char>& train,
                                          const Eigen::VectorXd& phi);

}  // namespace dyncal::host
