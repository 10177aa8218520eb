#pragma once
// Which parameters a log determines, decided from the data (docs/accuracy.md, "Real arms"). The
// structural base parameters (Gautier 1990) remove the combinations no motion can identify; a log
// that does not excite every remaining direction well enough still leaves some undetermined, and
// least squares then returns numbers (1e5 kg m^2 on a link of a few kg) with small *relative*
// standard deviations. The decision here compares each parameter's standard deviation with its
// physical scale (parameter_scales.hpp: the value at which its term alone reaches the joint's rated
// torque, or the robot file's inertial magnitude), at a stated confidence.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "dyncal_host/model/verdict.hpp"

namespace dyncal::host {

/// Least squares on the compressed problem min ||R phi - z||^2 (R: P x P upper triangular with
/// R^T R = W^T W of the weighted data, z the rotated right-hand side, rss the residual sum of
/// squares of the full model, rows the equations) restricted to the parameters the data determine.
struct DeterminedFit {
  Eigen::VectorXd phi;        ///< P; the dropped parameters held at 0
  Eigen::VectorXd stdev;      ///< P: sqrt(sigma2 inflation diag((W_K^T W_K)^-1)); NaN on the dropped ones
  Eigen::VectorXd gram_diag;  ///< P: diag((W_K^T W_K)^-1) of the kept parameters, NaN on the dropped ones
  double sigma2 = 0;          ///< RSS of the reduced model / (rows - kept)
  std::vector<int> dropped;   ///< not determined by the data, ascending
  /// Per dropped parameter (same order): when the kept parameters' columns explain at least half
  /// of its (scaled, weighted) column's squared norm, the kept parameters its effect is included in:
  /// the largest shares |coefficient| x column norm of that regression, at most 3, each at least a
  /// quarter of the largest (display only); empty: its column is mostly outside theirs (too little
  /// excited).
  std::vector<std::vector<int>> absorbed_into;
};

/// Drops, one at a time, the kept parameter whose kVerdictZ std most exceeds its scale (and first
/// any exactly dependent column, by QR with column pivoting of the column-scaled R), refitting after
/// each drop, until every kept parameter has kVerdictZ std <= scale: the largest model the log
/// determines (the "not determined" verdict of verdict_of never applies to a kept parameter).
/// `inflation` multiplies sigma2 in the decision and in stdev (the residual's autocorrelation factor
/// S / n_eff; 1 for white noise). `forced`: drop exactly these instead of deciding (the folds of a
/// cross-validation fit the model the full log decided). Throws InputError if no parameter is kept.
DeterminedFit determined_least_squares(const Eigen::MatrixXd& R, const Eigen::VectorXd& z, double rss, long rows,
                                       const Eigen::VectorXd& scale, double inflation = 1.0,
                                       const std::vector<int>* forced = nullptr);

/// One line naming the dropped parameters of `fit` (names: P parameter names): "Ia2 (included in
/// link2_ZZ_R), offset3 (too little excited)".
std::string dropped_parameters_text(const DeterminedFit& fit, const std::vector<std::string>& names);

}  // namespace dyncal::host
