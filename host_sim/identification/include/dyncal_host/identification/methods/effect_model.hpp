#pragma once
// A model with effect terms (model_effects.hpp) fitted and predicted at run time: the compiled
// regressor W of the declared terms, then the effects' columns E, and a least-squares fit of [W E]
// (OLS, IDIM-OLS, or WLS with Gautier's per-joint weights) with blocked cross-validation, as the
// compiled pipeline fits W alone.

#include <Eigen/Core>
#include <vector>

#include "dyncal_host/common/model_effects.hpp"
#include "dyncal_host/identification/pipeline/stacked_data.hpp"

namespace dyncal::host {

/// Number of columns of the effects (effect_param_names' counts summed).
Eigen::Index effect_column_count(const std::vector<ModelEffect>& effects);

/// Whether column `column` of `kind` (lib/ effect_columns) steps with the velocity's sign: Stribeck,
/// q_dot^(1/3), load friction, the asymmetric step [qd > 0], a coupled motor's sgn(v). Those are
/// built from the unfiltered velocity's sign and are low-passed once in time, as tau is; the
/// others are built from the filtered q, qd, qdd and have had the low-pass already.
bool effect_column_steps(EffectKind kind, int column);

/// effect_column_steps for every effect column (effect_column_count entries).
std::vector<bool> effect_columns_with_sign(const std::vector<ModelEffect>& effects);

/// The effects' columns over time for one segment (S samples; column j * m + c is joint j's row of
/// effect column c, m = effect_column_count), before parallel filtering: lib/ effect_columns at the
/// filtered q, qdd and at a velocity whose magnitude is the filtered qd's and whose sign is the
/// unfiltered velocity v_raw's, 0 inside the standstill band (as the pipeline's Coulomb columns;
/// a coupling's motor velocity qd_i + sign qd_j with the band sqrt(band_i^2 + band_j^2)). Load
/// friction's columns are left 0 (effect_design fills them).
Eigen::MatrixXd effect_columns_over_time(const std::vector<ModelEffect>& effects, const Eigen::MatrixXd& q,
                                         const Eigen::MatrixXd& qd, const Eigen::MatrixXd& qdd,
                                         const Eigen::MatrixXd& v_raw, const Eigen::VectorXd& band);

/// The effects' columns over stacked data ((S N) x m, row s * N + j, in the effects' order): d.E
/// (prepared with these effects; InputError otherwise), with load friction's columns |tau_rb|
/// sgn(qd) at the decimated samples (filtered qd, 0 at rest; tau_rb (S N) the transmitted
/// rigid-body torque [Nm], rigid_body_torque). A coupling's columns are on both of its joints (sign
/// times on the second: the motor's torque reflected by the transmission).
Eigen::MatrixXd effect_design(const StackedData& d, const std::vector<ModelEffect>& effects,
                              const Eigen::VectorXd& tau_rb);

/// The rigid-body torque (S N) [Nm] of parameters phi: the first num_base columns of W times the
/// first num_base entries of phi (what a drive's feed-forward gives load friction, drive_plant_of.hpp).
Eigen::VectorXd rigid_body_torque(const StackedData& d, const Eigen::VectorXd& phi);

/// [W E] for the parameters phi (W's P entries, then the effects'): load friction's rigid-body
/// torque taken from phi.
Eigen::MatrixXd model_design(const StackedData& d, const std::vector<ModelEffect>& effects, const Eigen::VectorXd& phi);

/// Fits [W E] to d by options.method (ols, wls, or pcls, gd, ga, pf: WLS made physically consistent,
/// consistent_least_squares.hpp, each link's inertials into res.links; InputError otherwise) with the validation of
/// `fold` (per sample: the fold it validates, -1 training only; `folds` folds): the out-of-fold
/// metrics into res.joints, the final fit's parameters (names: d.names then effect_param_names) with
/// standard deviations (white-noise figures times the residual's autocorrelation factor, as the
/// compiled pipeline) into res.params, cond into res.condition_number. Load friction's rigid-body
/// torque comes from a first fit of the same training rows without the load terms. Throws
/// InputError when [W E] is rank deficient on a training set.
void fit_effect_model(const StackedData& d, const std::vector<ModelEffect>& effects, const std::vector<int>& fold,
                      int folds, const RobotDescription& robot, const IdentifyOptions& options, IdentifyResult& res);

}  // namespace dyncal::host
