#pragma once
// One joint's friction fitted to its torque residual, for any robot: the velocity scale parameters
// (Stribeck velocity and its kin, survey Eq. 4-6) on a log grid, the amplitudes by least squares at
// each grid point (variable projection, Golub and Pereyra 1973), and each scale parameter's 95 %
// profile-likelihood interval.

#include <Eigen/Core>
#include <array>
#include <vector>

#include "dyncal_host/identification/methods/friction_parameters.hpp"

namespace dyncal::host {

/// Range of a velocity scale parameter of a joint whose fastest motion is max_speed [rad/s]:
/// [max(1e-3, 0.01 max_speed), max_speed] (two decades below the fastest motion).
std::array<double, 2> velocity_scale_range(double max_speed);
/// Range of scale parameter k of `model` for a joint's velocity_scale_range v: v itself for a
/// velocity, [1 / v[1], 1 / v[0]] for an inverse velocity (is_inverse_velocity).
std::array<double, 2> scale_parameter_range(FrictionModel model, int k, const std::array<double, 2>& v);

/// 95 % profile-likelihood interval of one scale parameter from fit_joint_friction's grid scan: the
/// grid values whose profiled squared residual SSE_k(v) (every other parameter at its best for
/// that value) keeps (SSE_k(v) - SSE_min) / sigma^2 * n_eff / S <= 3.84 (chi-square, 1 degree of
/// freedom), sigma^2 = SSE_min / (S - parameters), n_eff = effective_samples of the best residual
/// (filtered data are autocorrelated: S samples carry n_eff independent ones). lo, hi [the
/// parameter's unit]: the first grid values outside on either side (the searched range's end where
/// none is), so the interval is conservative by at most one grid step; open_below / open_above: the
/// interval reaches the end of the searched range, i.e. the data do not bound the parameter there.
struct ScaleInterval {
  int parameter = -1;  ///< index in friction_parameter_names
  double best = 0, lo = 0, hi = 0;
  bool open_below = false, open_above = false;
};

/// One joint's friction of `model` fitted to `target` (its torque less everything but the
/// friction) over its velocities qd [rad/s] and load torques load [Nm]: the scale parameters on a
/// log grid over scale_parameter_range (64 points for one, 16 x 16 for two), and at each point the
/// other parameters, on which the friction is linear there, by least squares (variable projection,
/// Golub and Pereyra 1973); the grid point with the least squared residual wins. Returns the
/// friction_parameter_names-ordered parameters, unclamped; each scale parameter's interval into
/// `intervals` if given.
std::vector<double> fit_joint_friction(FrictionModel model, const Eigen::VectorXd& qd, const Eigen::VectorXd& load,
                                       const Eigen::VectorXd& target, const std::array<double, 2>& velocity_range,
                                       std::vector<ScaleInterval>* intervals = nullptr);

}  // namespace dyncal::host
