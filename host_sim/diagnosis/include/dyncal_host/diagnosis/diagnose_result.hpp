#pragma once
// The options of `dyncal diagnose`, the effects it tests and what it found (diagnose.hpp).

#include <string>
#include <utility>
#include <vector>

#include "dyncal/effect_terms.hpp"
#include "dyncal_host/model/identify_options.hpp"
#include "dyncal_host/model/identify_result.hpp"

namespace dyncal::host {

struct DiagnoseOptions {
  IdentifyOptions identify;   ///< filtering, declared model (terms and effects), method (wls or ols), folds, blocks
  int max_effects = 16;       ///< greedy steps at most
  int max_cycles = 64;        ///< position-periodic search: 1..max_cycles cycles per revolution
  double bic_threshold = 10;  ///< accept when BIC falls by more than this (Kass-Raftery "very strong")
  double min_gain = 0.05;     ///< and the affected joints' validation RSS falls by at least this fraction
};

/// The effects the diagnosis tests. The catalogue's, all but drift, have a parameter-table term (lib/
/// EffectKind, whose columns they use), so a drive's feed-forward includes them; drift is a change
/// over the log (a temperature rise), not a model term; neither are the two beyond the catalogue (a
/// channel's delay, a shape: docs/diagnose.md "Beyond the catalogue").
enum class Effect {
  stribeck,             ///< extra torque at low speed: (Fs - Fc) sgn(qd) exp(-(qd / qds)^2)
  asymmetric_friction,  ///< friction that differs with the direction of motion
  velocity_power,       ///< f1 qd^(1/3) (Eq. 8)
  load_friction,        ///< f1 |tau_load| sgn(qd) (Eq. 9)
  rotor_inertia,        ///< Ia qdd
  offset,               ///< constant torque
  position_periodic,    ///< sin / cos of k q: cogging, gear ripple
  coupling,             ///< a motor turning with qd_i + r qd_j added to both joints (coupled transmission)
  coupled_motor,        ///< joint i's own motor turning with qd_i + r qd_j instead of qd_i (a coupled wrist)
  drift,                ///< viscous friction and offset changing linearly over the log
  // Beyond the catalogue (weighed when no kind above qualifies; no parameter-table term):
  torque_delay,  ///< the torque channel lagging the position channel by a delay (timing between channels)
  shape,         ///< a smooth function of one variable (cubic spline) no kind above explains as well
};

/// Stable lower-case name: "stribeck", "asymmetric_friction", ... (reports and JSON).
const char* effect_name(Effect e);

/// One effect added to the model.
struct DiagnosedEffect {
  Effect kind = Effect::offset;
  std::vector<int> joints;  ///< 1-based
  std::vector<std::string> param_names;
  std::vector<double> params;
  double shape = 0;  ///< velocity scale [rad/s] (stribeck), cycles per revolution (periodic), ratio |r| (coupling)
  std::pair<double, double> shape_interval{0, 0};  ///< 95 % profile interval of a searched shape (coupling ratio)
  double sign = 1;       ///< coupling: the motor turns with q_i + sign shape q_j, its torque on j times sign shape
  double delta_bic = 0;  ///< BIC change on the affected joints (negative: evidence for)
  double validation_gain = 0;  ///< relative drop of the affected joints' validation RSS
  std::string explanation;
  std::vector<std::string> alternatives;  ///< kinds on the same joints the data cannot tell from this one
  /// coupling, coupled_motor: the motor's rotor inertia is held at 0 (its free fit is negative; not
  /// among param_names, 0 in the drive table's coupling term)
  bool inertia_held = false;
  std::string variable;       ///< shape: the variable its spline is of
  std::vector<double> knots;  ///< shape: the spline's full knot vector (boundaries repeated 4 times)
  /// shape: its roughness penalty lambda (model_effects.hpp's ModelEffect::penalty; 0: none)
  double penalty = 0;
  /// The parameters it adds as its evidence counted them: a penalised shape's effective ones (the
  /// trace of the hat matrix that is its), else its coefficients less the columns it replaces.
  double effective_parameters = 0;
  /// shape: the function found at kShapeCurvePoints (spline_basis.hpp) points evenly over the knots' span (curve_x, in
  /// the variable's unit) and its torque there (curve_y [Nm]; times sgn(qd) where the variable
  /// carries the sign), for the reports' plots
  std::vector<double> curve_x, curve_y;
  /// shape: curve_y's pointwise 95 % band [Nm] (the delete-a-group jackknife over the folds' fits,
  /// Student's t; beyond_catalogue.hpp shape_band)
  std::vector<double> curve_lo, curve_hi;
  /// The share of the affected joints' excess validation RSS this effect removed: the drop it made
  /// over what was left above the noise floor before it (DiagnoseJoint::rms_noise_floor).
  double excess_share = 0;
  /// Its 95 % interval, as DiagnoseJoint::excess_left_interval's
  std::pair<double, double> excess_share_interval{0, 0};
};

struct RejectedCandidate {
  Effect kind = Effect::offset;
  std::vector<int> joints;
  double delta_bic = 0, validation_gain = 0;
  std::string reason;
};

struct DiagnoseJoint {
  int joint = 0;
  double rms_train_before = 0, rms_train_after = 0;
  double rms_validation_before = 0, rms_validation_after = 0;
  double rms_tau = 0;
  double r2_validation_before = 0, r2_validation_after = 0;
  /// mean and std of |tau - tau_hat| / tau_max (not the survey's e_T, the |mean| of the signed error)
  double e_T_abs_before = 0, e_T_abs_after = 0, e_T_abs_std_before = 0, e_T_abs_std_after = 0;
  /// The validation RMS a perfect model would leave [Nm]: the log's white torque noise through the
  /// identification's low-pass (noise_floor.hpp), on the same rows
  double rms_noise_floor = 0;
  std::pair<double, double> rms_noise_floor_interval{0, 0};  ///< its 95 % interval [Nm] (noise_floor.hpp)
  /// The share of the declared model's excess validation RSS (above the floor) still left after the effects
  double excess_left = 1;
  /// Its 95 % interval: the folds' jackknife around the shares the floor's interval gives (diagnose.cpp)
  std::pair<double, double> excess_left_interval{1, 1};
};

/// What the plots show, per joint (kept samples, decimated rate).
struct DiagnoseTraces {
  Eigen::VectorXd t;
  Eigen::MatrixXd q, qd, tau, tau_before, tau_after;  ///< S x N; predictions of the final fits
  Eigen::MatrixXd spectrum;  ///< max_cycles x N: residual power removed by k cycles/rev (declared model)
};

struct DiagnoseResult {
  std::string robot, declared_model, validation;
  std::string method;  ///< wls (Gautier's per-joint weights, from the declared model's OLS residual) or ols
  long samples = 0;
  double effective_samples_per_joint = 0;  ///< n_eff used by BIC: duration x 2 f_c
  std::vector<DiagnoseJoint> joints;
  std::vector<DiagnosedEffect> effects;
  std::vector<RejectedCandidate> rejected;  ///< best candidate per kind and joint of the last round
  std::vector<std::string> notes;
  std::vector<std::string> declared_names;  ///< the declared model's parameters...
  std::vector<double> declared_params;      ///< ...re-estimated jointly with the effects found
  DiagnoseTraces traces;
};

}  // namespace dyncal::host
