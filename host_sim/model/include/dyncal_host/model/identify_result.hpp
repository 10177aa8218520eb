#pragma once
// What an identification reports: per-joint metrics, parameter estimates with their verdicts, the
// prediction of other logs, consistent link inertials (identify(), the reports, the parameter files).

#include <array>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "dyncal_host/model/verdict.hpp"

namespace dyncal::host {

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
  std::vector<LogPrediction> other_logs;    ///< --validate-on: the final fit's prediction of each other log
  std::vector<LinkInertial> links;          ///< pcls: the final fit's consistent inertials per link
  std::vector<double> tau_model_reference;  ///< shapes of tau_model: the reference parameters (ParameterSet's)
  /// The blocked cross-validation's fits, each without one fold (params' order and count; none with
  /// --validate-last): the delete-a-group jackknife's replicates of the shapes' bands.
  std::vector<std::vector<double>> fold_params;
  bool friction_per_motor = false;  ///< a coupled motor's terms act on several joints (robot.json's coupling)
  /// 1-based joints that are prismatic: their torques are forces [N], their Fc [N], Fv [N s/m], Ia [kg].
  std::vector<int> prismatic_joints;
};

}  // namespace dyncal::host
