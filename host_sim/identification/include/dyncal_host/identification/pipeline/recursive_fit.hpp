#pragma once
// The streaming estimators of any robot's identification model at the model's run-time size,
// compiled once for every robot and term set: lib/ StreamingLeastSquares (identify's IDIM-OLS / WLS),
// and KalmanFilter and RlsForgetting (identify --method kf | rls, calibrate's online path), these
// once per joint count.

#include <memory>

#include "dyncal/parameter_table.hpp"
#include "dyncal/status.hpp"
#include "dyncal_host/model/term_set_model.hpp"

namespace dyncal::host {

/// Most parameters of a model of `num_joints` joints: 10 standard parameters and one column per
/// term (dyncal::kNumTerms) a joint. The run-time filters' capacity.
constexpr int max_model_params(int num_joints) {
  return (10 + kNumTerms) * num_joints;
}

/// The run-time least squares' capacity: a drive's parameter table's (lib/ parameter_table.hpp; a
/// larger model could not be flashed), room beside a 7-joint model's declared parameters for the
/// effect columns a diagnosis adds (a penalised shape has 27). Eigen's largest fixed-size matrix
/// (128 KiB) holds its triangular factor.
inline constexpr int kMaxFitParams = kTableMaxParams;
static_assert(kMaxFitParams >= max_model_params(kMaxRobotJoints), "the least squares hold every declared model");

/// lib/ StreamingLeastSquares<double, Eigen::Dynamic> (IDIM-OLS / WLS, survey Eq. 15) of `model`'s
/// size P = model.num_params, capacity kMaxFitParams, with no rows. Throws
/// InputError for a model beyond that capacity.
std::unique_ptr<LeastSquaresFit> make_least_squares(const TermSetModel& model);

/// lib/ KalmanFilter<double, Eigen::Dynamic, N> (survey Eq. 19) of `model`'s size (N =
/// model.num_joints, P = model.num_params, dense regressor structure), reset to phi = 0 with
/// covariance diag(p0). Null with the filter's status in *status when reset refuses p0 (not
/// positive or not finite).
std::unique_ptr<RecursiveFit> make_kalman_filter(const TermSetModel& model, double p0, UpdateStatus* status);

/// lib/ RlsForgetting<double, Eigen::Dynamic, N> (survey Eq. 23) of `model`'s size, reset to
/// phi = 0, covariance diag(p0) and forgetting factor mu in (0, 1]. Null with the status in *status
/// when reset refuses p0 or mu.
std::unique_ptr<RecursiveFit> make_rls(const TermSetModel& model, double p0, double mu, UpdateStatus* status);

}  // namespace dyncal::host
