#pragma once
// The survey's six friction models (Eq. 4-9) as the study parameterises one joint: parameter names
// and order, set values, torque with its gradient, which parameters enter linearly with a fixed
// column (the rest is the nonlinear part the solvers treat apart), and which are scale parameters
// (velocities or inverse velocities, searched on a log scale and kept > 0).

#include <string>
#include <vector>

#include "dyncal_host/common/friction_model.hpp"

namespace dyncal::host {

/// The six models in the study's order: linear Eq. 7, 8, 9, nonlinear Eq. 4, 5, 6.
inline constexpr FrictionModel kLinearModels[] = {FrictionModel::eq7, FrictionModel::eq8, FrictionModel::eq9};
inline constexpr FrictionModel kNonlinearModels[] = {FrictionModel::eq4, FrictionModel::eq5, FrictionModel::eq6};

/// "eq4" .. "eq9".
const char* model_key(FrictionModel model);
/// Eq. 7, 8, 9: every parameter multiplies a fixed column (survey Eq. 10).
bool is_linear(FrictionModel model);

/// Parameter names per joint, in the study's order:
///   Eq. 7 {Fc, beta}; Eq. 8 {Fc, beta, fp}; Eq. 9 {Fc, beta, fl};
///   Eq. 4 {Fc, Fs, qds, beta}; Eq. 5 {f1, f2, f3, f4, f5, beta}; Eq. 6 {f1, f2, f3, f4, beta}.
/// Units: Fc, Fs, f1, f2, f4 (Eq. 5) [Nm]; beta [Nm s/rad]; fp [Nm (s/rad)^(1/3)]; fl [-];
/// qds, f3 (Eq. 5) [rad/s]; f5 (Eq. 5), f3, f4 (Eq. 6) [s/rad].
std::vector<std::string> friction_parameter_names(FrictionModel model);
int friction_count(FrictionModel model);

/// Scale parameters: qds (Eq. 4), f3 and f5 (Eq. 5), f3 and f4 (Eq. 6).
bool is_scale_parameter(FrictionModel model, int k);
/// A scale parameter's velocity form: true if it is an inverse velocity [s/rad] (f5 of Eq. 5,
/// f3 and f4 of Eq. 6), false if a velocity [rad/s].
bool is_inverse_velocity(FrictionModel model, int k);

/// Parameter k multiplies a fixed column basis(qd, tau_load) in the model: Fc / f1 -> sgn(qd)
/// (Eq. 4, 5, 7, 8, 9), beta -> qd, fp -> qd^(1/3), fl -> |tau_load| sgn(qd).
bool is_linear_parameter(FrictionModel model, int k);
double linear_column(FrictionModel model, int k, double qd, double tau_load);

/// Friction torque [Nm] of one joint with parameters theta (friction_parameter_names order) at
/// velocity qd [rad/s] and load torque tau_load [Nm] (read by Eq. 9 only); gradient d tau_f /
/// d theta into grad (friction_count) if not null. Scale parameters below 1e-3 act as 1e-3 (lib/
/// NonlinearFriction's projection).
double friction_torque(FrictionModel model, const double* theta, double qd, double tau_load, double* grad = nullptr);

}  // namespace dyncal::host
