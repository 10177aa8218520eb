#pragma once
// A model with effect terms (model_effects.hpp) at run time: the compiled regressor W of the declared
// terms, then the effects' columns E, appended so that identification fits [W E] by the same
// pipeline, prior and validation as W alone (identify_pipeline.hpp).

#include <Eigen/Core>
#include <vector>

#include "dyncal_host/common/model_effects.hpp"
#include "dyncal_host/model/stacked_data.hpp"
#include "dyncal_host/model/term_set_model.hpp"

namespace dyncal::host {

struct RobotDescription;

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

/// The values (S) at d's kept samples of a shape's variable v (model_effects.hpp): t - t[0] [s],
/// the filtered q, qd or qdd of v.joint, or tau_model_joint (S, the model's torque of the shape's
/// joint [Nm]) for tau_model (the diagnosis's; no model term reads it); the friction sign is not
/// applied (shape_series does).
Eigen::VectorXd shape_variable_values(const StackedData& d, const ShapeVariable& v,
                                      const Eigen::VectorXd& tau_model_joint);

/// A shape's columns (S x (knots.size() - 5), spline_basis.hpp's shape_basis) on joint `joint` at
/// the values x of its variable v (shape_variable_values); for a sign product, times the friction
/// sign of the joint's unfiltered velocity (d.qd_raw, 0 inside d.standstill_band) and then
/// low-passed in time as the friction columns were (d.filter_order, d.cutoff_hz at d.rate_hz, zero
/// phase, inside each of time_segments(d)). One implementation for diagnose's shape candidates,
/// identify's shape effects and predict. Throws InputError when a sign product meets data without
/// d.qd_raw.
Eigen::MatrixXd shape_series(const StackedData& d, int joint, const ShapeVariable& v, const Eigen::VectorXd& x,
                             const std::vector<double>& knots);

/// The effects' columns over stacked data ((S N) x m, row s * N + j, in the effects' order): d.E
/// (prepared with these effects; InputError otherwise), with load friction's columns |tau_rb|
/// sgn(qd) at the decimated samples (filtered qd, 0 at rest; tau_rb (S N) the transmitted
/// rigid-body torque [Nm], rigid_body_torque) and each shape's shape_series (a shape of tau_model
/// reads tau_model (S N) [Nm], the model's torque without the shapes of it; its columns stay 0 when
/// tau_model is empty). A coupling's columns are on both of its joints (sign times on the second:
/// the motor's torque reflected by the transmission).
Eigen::MatrixXd effect_design(const StackedData& d, const std::vector<ModelEffect>& effects,
                              const Eigen::VectorXd& tau_rb, const Eigen::VectorXd& tau_model = Eigen::VectorXd());

/// The rigid-body torque (S N) [Nm] of parameters phi: the first num_base columns of W times the
/// first num_base entries of phi (what a drive's feed-forward gives load friction, drive_plant_of.hpp).
Eigen::VectorXd rigid_body_torque(const StackedData& d, const Eigen::VectorXd& phi);

/// [W E] for the parameters phi (W's P entries, then the effects'): load friction's rigid-body
/// torque taken from phi; a shape of tau_model's variable the torque of `reference` (ParameterSet's
/// tau_model_reference, phi's layout, 0 at those shapes). Throws InputError when a shape of tau_model
/// has no reference of phi's size.
Eigen::MatrixXd model_design(const StackedData& d, const std::vector<ModelEffect>& effects, const Eigen::VectorXd& phi,
                             const Eigen::VectorXd& reference = Eigen::VectorXd());

/// Appends the effects' columns to d's regressor, for the identification pipeline to fit them as it
/// fits the declared terms (one least-squares implementation: identify_pipeline.hpp): W becomes
/// [W(:, 0..declared) E(:, use)] and names gains effect_param_names of the used columns; the
/// regressor's rows are then read from the dense W (W_load is cleared: none with effects). E is
/// effect_design(d, effects, tau_rb, tau_model); use: per effect column (effect_column_count
/// entries), whether it is appended. Throws InputError as effect_design.
void set_effect_columns(StackedData& d, Eigen::Index declared, const std::vector<ModelEffect>& effects,
                        const std::vector<bool>& use, const Eigen::VectorXd& tau_rb,
                        const Eigen::VectorXd& tau_model = Eigen::VectorXd());

/// `model` with the used effect columns' parameters appended (set_effect_columns' order): names,
/// and ParamInfo of a term of the effect's first joint (parameter_scales judges it on that joint's
/// tau_max); no compiled regressor (its rows come from StackedData::W).
TermSetModel with_effect_parameters(const TermSetModel& model, const std::vector<ModelEffect>& effects,
                                    const std::vector<bool>& use);

/// A penalised shape's roughness penalty on a fit of [W E] (model_effects.hpp's ModelEffect::penalty):
/// joint j's weighted RSS gains w_j^2 n_j lambda |L c|^2, with c the shape's coefficients (its m
/// columns from `column` on), L its shape_roughness_rows (|L c|^2 the integral of f''^2) and n_j the
/// joint's fitted rows in that fit. In least squares: the rows sqrt(n_j lambda) L on those columns,
/// right-hand side 0, weighed as joint j's rows (O'Sullivan's penalised regression spline).
struct ShapePenalty {
  int joint = 0;            ///< 0-based
  Eigen::Index column = 0;  ///< the shape's first column in [W E]
  double lambda = 0;        ///< ModelEffect::penalty
  Eigen::MatrixXd rows;     ///< L: r x m
};

/// The penalties of the penalised shapes among `effects` whose columns are appended (`use`, as
/// set_effect_columns), their columns counted from `declared`.
std::vector<ShapePenalty> shape_penalties(const std::vector<ModelEffect>& effects, const std::vector<bool>& use,
                                          Eigen::Index declared);

/// The physical scale of each appended effect parameter (identifiability.hpp's verdicts), entries
/// declared .. P-1 of `model` (with_effect_parameters) over d (set_effect_columns): the value at which
/// its column, at its largest on the effect's joint in this log, gives that joint's tau_max [Nm; N].
Eigen::VectorXd effect_parameter_scales(const StackedData& d, Eigen::Index declared, const TermSetModel& model,
                                        const RobotDescription& robot);

/// Per effect column: false where it reads the model's own torque (load friction's rigid-body
/// torque, a shape of tau_model: they need a first fit), true for every other.
std::vector<bool> effect_columns_without_model_torque(const std::vector<ModelEffect>& effects);

}  // namespace dyncal::host
