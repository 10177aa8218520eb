#pragma once
// The survey's model choice (Sec. 6.6, Table 12) on a measured log: each of the six friction models
// (Eq. 4-9) fitted together with the declared non-friction model to the first part of the log, and
// judged on the torque error there and on the final part, which the fit did not see.

#include <iosfwd>
#include <string>
#include <vector>

#include "dyncal_host/common/friction_model.hpp"
#include "dyncal_host/identification/methods/friction_fit.hpp"
#include "dyncal_host/model/stacked_data.hpp"

namespace dyncal::host {

struct FrictionModelFit {
  std::string others;  ///< the non-friction columns' names, comma-separated
  FrictionModel model = FrictionModel::eq7;
  int parameters = 0;                              ///< friction parameters (all joints)
  double fit_mean = 0, fit_std = 0;                ///< torque error on the fitted rows [Nm], pooled over joints
  double validation_mean = 0, validation_std = 0;  ///< on the held-out final rows [Nm]
  std::vector<double> friction;                    ///< joint-major, friction_parameter_names order
  /// Nonlinear models: per joint, each scale parameter's 95 % profile-likelihood interval from the
  /// last round's scan (ScaleInterval; open where the log does not bound it).
  std::vector<std::vector<ScaleInterval>> scale_intervals;
};

/// `data`: stacked data of any built model; its friction columns (named Fc, Fv, Fp, Fl + joint) are
/// dropped, the rest (base parameters, rotor inertia, offsets) kept with every model. The first (1 - validate_last) of
/// the samples fit, the rest validate. Linear models (Eq. 7, 8, 9) by least squares with their columns added; Eq. 9's
/// load torque is the fitted non-friction torque of the Eq. 7 fit (a log has no separate gravity torque). Nonlinear
/// models (Eq. 4, 5, 6) by separable least squares: from the Eq. 7 fit, each joint's scale parameters from a log grid
/// over their ranges (velocity_scale_range of the log's speeds) with the amplitudes fitted at each point
/// against the joint's non-friction residual, then one least-squares fit of every column at the chosen scales; two
/// rounds. Throws InputError if validate_last is not in (0, 1) or the data are too short.
std::vector<FrictionModelFit> compare_friction_models(const StackedData& data, double validate_last);

/// Prints the comparison: one row per model, friction parameters, torque error mean / std [Nm] on
/// the fitted part and std on the held-out part, and which model the held-out std prefers; then the
/// nonlinear models' scale parameters per joint with their intervals.
void print_friction_comparison(std::ostream& out, const std::vector<FrictionModelFit>& fits, double validate_last);

}  // namespace dyncal::host
