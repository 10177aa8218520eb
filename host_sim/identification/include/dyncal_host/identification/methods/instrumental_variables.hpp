#pragma once
// IDIM-IV for any robot (identify --method iv; survey Eq. 17; Gautier, Janot and Vandanjon 2013):
// phi = (Z^T W K)^-1 Z^T W tau, K the regressor of the measured, filtered states and Z the same
// regressor of the states a closed-loop simulation of the drive's known control law produces with
// the previous estimate as the plant, iterated to convergence. The instruments do not see the
// measurement noise of q, so it does not bias the estimate as it biases least squares.

#include <functional>
#include <vector>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/model/identify_options.hpp"
#include "dyncal_host/model/identify_result.hpp"
#include "dyncal_host/model/stacked_data.hpp"

namespace dyncal::host {

/// Prepares a log as the measured one was (the identify pipeline's prepare, dense W, the measured
/// log's standstill band: the instruments' friction-sign columns are 0 where the measured ones are).
using PrepareLog = std::function<StackedData(JointLog&&)>;

/// Closed-loop simulations at most, and the convergence test: an iteration moving the estimate by
/// at most kIvTolerance of its standard errors (RMS over the parameters, in the IV covariance) ends
/// it; such a step adds about kIvTolerance^2 (1 %) to the estimate's variance.
inline constexpr int kIvMaxSimulations = 20;
inline constexpr double kIvTolerance = 0.1;

/// identify's IDIM-IV on data `d` prepared (dense) from a log on the grid `grid` (its t, segments
/// and period: the simulated logs' grid), for the rigid body with Coulomb and viscous friction per
/// joint (Eq. 7). Rows weighted per joint by 1 / the OLS residual's std (Gautier). Starts from the
/// WLS fit; each iteration's plant: the physically consistent standard parameters nearest that
/// iterate in the weighted data's metric, robot.json's inertials as the prior for what the data do
/// not see (consistent_least_squares), Fc, Fv >= 0; simulated by options.closed_loop, prepared by
/// `prepare`. Half steps once a step fails to halve the previous one (the map can cycle). Cross-
/// validation (`fold`, `folds`) refits the IV estimate with the final instruments on each training
/// part. Parameter std: the IV covariance s^2 (Z^T K)^-1 Z^T Z (K^T Z)^-1 inflated by the residual's
/// autocorrelation. Fills res (joints, params, condition number, notes: simulations run, converged
/// or not, last step in standard errors). `dropped`: the parameters the log does not determine (the
/// WLS fit's decision, identifiability.hpp): the iteration's plants come from the whole model, the
/// reported estimate and its cross-validation hold each at held_at[i] (P: the robot's prior mean
/// where it has one, else 0; ParameterPrior) with std NaN. Throws InputError: no
/// closed loop, a term set other than Eq. 7, a coupled motor's friction (use --friction-per-joint),
/// a simulation that trips the drive.
void fit_instrumental(const StackedData& d, const JointLog& grid, const std::vector<int>& fold, int folds,
                      const RobotDescription& robot, const IdentifyOptions& options, const PrepareLog& prepare,
                      const std::vector<int>& dropped, const Eigen::VectorXd& held_at, IdentifyResult& res);

}  // namespace dyncal::host
