#pragma once
// The Gaussian prior of a model's parameters from its robot folder, for the default least-squares
// fit's maximum a posteriori estimate (identify --method wls/ols, --prior-std): data where the data
// speak, the robot's CAD values where they do not, instead of holding what the log does not
// determine at 0.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "dyncal_host/model/term_set_model.hpp"

namespace dyncal::host {

struct RobotDescription;

/// N(mean, Sigma) on the parameters that have a prior. The base parameters' prior is that of
/// robot.json's inertials (the standard parameters phi0, each with std prior_std(phi0,
/// relative_std), consistent_least_squares.hpp) carried through Gautier's base map K:
/// mean K phi0, Sigma = K diag(s^2) K^T (full: base parameters share standard ones). A joint's
/// Coulomb Fc [Nm; N] and viscous Fv [Nm s/rad; N s/m] columns have robot.json's "friction" values
/// (Fc, beta) where they are > 0, each with std relative_std times the value, independent of the
/// rest; not for a motor that turns with other joints (robot.json's friction is per joint). Rotor
/// inertia, offsets, the power term and effect terms have none (a robot folder holds no value).
struct ParameterPrior {
  Eigen::VectorXd mean;      ///< P; 0 where a parameter has no prior (has[i] false)
  Eigen::VectorXd variance;  ///< P: diag(Sigma); NaN where no prior
  /// R x P: whitening (phi - mean) ~ N(0, I); rows: the B base parameters' block (when the robot has
  /// inertials), then one row per friction prior.
  Eigen::MatrixXd whitening;
  std::vector<char> has;  ///< P: parameter i has a prior
  /// Why the inertials give none (a robot file without inertials, --prior-std 0); empty when they do.
  std::string missing;
  bool usable() const { return whitening.rows() > 0; }
};

/// The prior of `model`'s parameters for `robot` with the inertials' relative std `relative_std`
/// (<= 0: none). A robot whose inertials are all 0 has none (missing says so).
ParameterPrior parameter_prior(const RobotDescription& robot, const TermSetModel& model, double relative_std);

/// Adds the prior to `ls` as pseudo-rows whitening.row(b) phi = whitening.row(b) mean, each with
/// weight sigma (the data rows' residual std in their weighted units): ls then solves
/// min ||W phi - y||^2 / sigma^2 + ||whitening (phi - mean)||^2, the MAP estimate, whose inverse
/// Gram matrix times sigma^2 is the posterior covariance (Gaussian noise of variance sigma^2).
/// Returns lib/'s status of the first row it refuses (sigma <= 0 or not finite), ok otherwise.
UpdateStatus add_prior_rows(LeastSquaresFit& ls, const ParameterPrior& prior, double sigma);

/// The MAP estimate's statistics over the parameters not in `held` (fixed: std 0, share NaN). The
/// estimate weighs the data rows `data_weight` times as white noise of variance sigma2: with
/// D = R^T R / sigma2 and Q = whitening^T whitening, H = data_weight D + Q and
/// phi = H^-1 (data_weight R^T z / sigma2 + Q mean). R: P x P, the data's triangular factor
/// (R^T R = W^T W of the weighted rows).
struct PriorFitStatistics {
  /// P: sqrt(diag(H^-1 (data_weight^2 inflation D + Q) H^-1)): the estimate's spread when the
  /// data's noise is `inflation` times its white variance (the residual's autocorrelation,
  /// S / n_eff) and the truth is a draw from the prior (a sandwich covariance).
  Eigen::VectorXd stdev;
  /// P: the share of the estimate that comes from the data, 1 - (H^-1 Q)_ii clamped to [0, 1] (the
  /// prior mean's influence on parameter i removed); NaN without a prior.
  Eigen::VectorXd data_share;
};
PriorFitStatistics prior_fit_statistics(const ParameterPrior& prior, const Eigen::MatrixXd& R, double sigma2,
                                        double inflation, double data_weight, const std::vector<int>& held);

}  // namespace dyncal::host
