#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "dyncal_host/common/model_effects.hpp"
#include "dyncal_host/common/model_terms.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/identification/logs/joint_log.hpp"
#include "dyncal_host/identification/methods/identifiability.hpp"

namespace dyncal::host {

/// Options of `dyncal identify` (defaults follow the survey and Gautier's practice).
/// Highest Butterworth order identify accepts (even orders, cascaded second-order sections).
inline constexpr int kMaxFilterOrder = 8;

/// Options of identify(); each is range-checked against the log before any work (InputError naming
/// the option and its admissible range).
struct IdentifyOptions {
  /// wls (Gautier's per-joint weights) | ols (IDIM-OLS) | kf | rls | pcls (physically consistent WLS) |
  /// gd | ga | pf (the survey's optimisers on the weighted data: search_consistent) | iv (IDIM-IV:
  /// instrumental_variables.hpp, needs closed_loop)
  std::string method = "wls";
  unsigned terms = 0;                ///< dyncal::term bits (rigid body always included)
  std::vector<ModelEffect> effects;  ///< effect terms after the compiled ones (model_effects.hpp): not kf, rls
  std::vector<CoupledMotor> motors;  ///< coupled motors (model_effects.hpp): rows of the motor-velocity map
  int filter_order = 4;              ///< Butterworth order (zero-phase: twice the attenuation)
  double cutoff_hz = 20.0;           ///< low-pass cut-off for q, tau and the regressor columns
  int decimate = 0;                  ///< decimation factor; 0: floor(fs / (25 * cutoff)), at least 1
  int folds = 5;                     ///< blocked k-fold cross-validation
  double block_seconds = 0.5;        ///< length of the contiguous blocks dealt to the folds in turn
  double validate_last = 0.0;        ///< > 0: plain time split, this fraction at the end validates
  double rls_mu = 0.9999;            ///< forgetting factor of RLS (survey Eq. 23)
  double p0 = 1e6;                   ///< initial covariance diag of KF and RLS (prior ignorance)
  double min_speed_fraction = 0.0;   ///< fit only rows with |qd_j| >= this fraction of joint j's top speed
  bool load_regressor = false;       ///< also stack Y(q, qd, 0) (StackedData::W_load): the load torque's regressor
  double prior_std = 0.5;      ///< pcls: the prior's relative std (kPriorRelativeStd); 0: no prior, consistency alone
  double range_width = 3.0;    ///< gd, ga, pf: standard parameters within nominal +- this x their scale
  std::uint64_t seed = 1;      ///< ga, pf: random seed
  int search_evaluations = 0;  ///< gd: cost evaluations, ga: generations, pf: evaluations per particle; 0: default
  bool friction_per_joint = false;  ///< ignore robot.json's coupling: friction and rotor inertia per joint (the log's
                                    ///< conversion still uses the transmission); lets diagnose rediscover a coupling
  /// wls, ols: Coulomb and viscous friction and rotor inertia held >= 0 (sign_constrained.hpp:
  /// Lawson-Hanson on the weighted data's triangular factor), what a drive's table must hold
  /// (lib/ table_check.hpp); a parameter held at 0 is named in the notes, its std 0.
  bool sign_constraints = false;
  /// Refuse (InputError, exit 2) a log that leaves a parameter of the model not determined
  /// (identifiability.hpp) instead of dropping it with a note.
  bool strict = false;
  /// iv: the closed-loop simulation of the logged run under the drive's known control law (identify
  /// --law; drive_law.hpp): the log's grid (t, segments, period) with q the plant's positions at its
  /// samples (tau 0), the plant's standard parameters phi_standard (10 N, generated order) and
  /// Coulomb Fc [Nm] and viscous Fv [Nm s/rad] friction per joint (N). Throws InputError (a trip).
  std::function<JointLog(const JointLog& grid, const Eigen::VectorXd& phi_standard, const Eigen::VectorXd& Fc,
                         const Eigen::VectorXd& Fv)>
      closed_loop;
};

struct JointMetrics {
  int joint = 0;            ///< 1-based
  double rms = 0;           ///< RMS of the validation residual [Nm]
  double rms_tau = 0;       ///< RMS of the measured torque [Nm]
  double relative_rms = 0;  ///< rms / rms_tau
  double r2 = 0;            ///< 1 - SS_res / SS_tot
  /// mean and std of |tau - tau_hat| / tau_max: the absolute error beside the survey's e_T (Sec.
  /// 5.1, |mean of the signed error|, docs/survey.md), named apart from it
  double e_T_abs = 0, e_T_abs_std = 0;
};

struct ParamEstimate {
  ParamEstimate() = default;
  ParamEstimate(std::string name_, double value_, double std_) : name(std::move(name_)), value(value_), std(std_) {}
  std::string name;
  double value = 0;
  /// Standard deviation (OLS/WLS: sigma^2 (W^T W)^-1, with a prior the posterior's; KF/RLS:
  /// sqrt(diag P)); NaN: held at 0.
  double std = 0;
  /// Physical scale (parameter_scales.hpp) the verdict compares the std with; 0: not judged (the
  /// effect terms' parameters of a model with effects).
  double scale = 0;
  /// From the data's std (for pcls, gd, ga, pf: the weighted least-squares std, not the prior's):
  /// identifiability.hpp.
  Verdict verdict = Verdict::determined;
  /// What a not-determined parameter's value rests on: "prior" (ols, wls: the MAP estimate with
  /// robot.json's inertials, parameter_prior.hpp; pcls: its prior), "held at 0" (no prior covers it:
  /// dropped from the least-squares fit, its effect is in the combination the log determines),
  /// "least squares" (no prior covers it; the data's own wide estimate), "search" (gd, ga, pf: the
  /// search's start and range), "start" (kf, rls: the filter's initial 0), "sign constraint" (any
  /// verdict: --sign-constraints holds it at exactly 0, the free fit having it below 0); empty when
  /// the data determine it.
  std::string basis;
  /// ols, wls with a prior: the share of the estimate that comes from the data, in [0, 1] (1 - the
  /// prior mean's influence on it, parameter_prior.hpp); NaN without a prior.
  double data_share = std::numeric_limits<double>::quiet_NaN();
  /// A Coulomb, viscous or rotor-inertia term (nonnegative_terms) below 0 by more than its 95 %
  /// interval: the data contradict physics there (printed so, never as "determined").
  bool contradicts_physics = false;
};

/// A model's prediction of a log it was not fitted to (identify --validate-on, dyncal predict).
struct LogPrediction {
  std::string source;
  long samples = 0;  ///< samples compared (after filtering and decimation)
  std::vector<JointMetrics> joints;
  std::vector<std::string> notes;  ///< the log's sampling and standstill notes
};

/// One link's identified inertials (identify --method pcls): Table 5's parametrisation of its
/// consistent standard parameters, link frame (Khalil-Kleinfinger).
struct LinkInertial {
  int link = 0;                     ///< 1-based
  double mass = 0;                  ///< [kg]
  std::array<double, 3> com{};      ///< centre of mass [m]
  std::array<double, 6> inertia{};  ///< about the centre of mass: I11 I12 I13 I22 I23 I33 [kg m^2]
  double min_eigenvalue = 0;        ///< smallest eigenvalue of the pseudo-inertia (> 0: consistent)
  /// Standard deviations of mass, com and inertia (pcls: the delta method on the fit's covariance,
  /// autocorrelation-inflated); NaN where the fit gives none (the searches, an older file).
  double mass_std = std::numeric_limits<double>::quiet_NaN();
  std::array<double, 3> com_std{kNoStd, kNoStd, kNoStd};
  std::array<double, 6> inertia_std{kNoStd, kNoStd, kNoStd, kNoStd, kNoStd, kNoStd};
  static constexpr double kNoStd = std::numeric_limits<double>::quiet_NaN();
  /// What the mass rests on: "data" (its 95 % interval excludes 0), "prior" (it does not, and the fit
  /// had robot.json's prior), "neither" (no prior: nothing fixes it; export refuses it); empty when
  /// the fit gives no std.
  std::string mass_basis;
};

struct IdentifyResult {
  std::string robot, method, model, validation, data_source;
  double sample_rate_hz = 0, decimated_rate_hz = 0, cutoff_hz = 0;
  long samples_used = 0;
  std::vector<JointMetrics> joints;
  std::vector<ParamEstimate> params;
  double condition_number = 0;  ///< cond(W) of the full stacked (weighted) regressor
  double fit_seconds = 0;       ///< wall time of the estimator over the full data
  std::vector<std::string> notes;
  std::vector<LogPrediction> other_logs;  ///< --validate-on: the final fit's prediction of each other log
  std::vector<LinkInertial> links;        ///< pcls: the final fit's consistent inertials per link
  bool friction_per_motor = false;        ///< a coupled motor's terms act on several joints (robot.json's coupling)
  /// 1-based joints that are prismatic: their torques are forces [N], their Fc [N], Fv [N s/m], Ia [kg].
  std::vector<int> prismatic_joints;
};

/// Identifies the model from `log` and validates it on data each fit never saw.
/// Throws InputError on bad options (see check in identify.cpp: filter order, cut-off below Nyquist
/// and above 2 / duration, folds >= 2 with blocks of at least one cut-off period, validate_last in
/// (0, 0.9] covering at least one cut-off period, mu in (0, 1], p0 > 0), too little data, a robot not compiled into
/// this build (compiled_robot.hpp) or a model not built (model_terms.hpp). Pass the log with
/// std::move when it is not needed afterwards: a uniform log is then processed without a copy.
IdentifyResult identify(const RobotDescription& robot, JointLog log, const IdentifyOptions& options);

}  // namespace dyncal::host
