#pragma once
// The robot-specific half of `dyncal calibrate`: lib/'s fixed-size estimators (KF, RLS with
// forgetting, causal differentiator) for one robot's identification models, and the verification
// of a parameter vector on a fresh log. One implementation per robot folder (online_model_of.hpp)
// registers itself by name when the program starts (host_sim/robots/).

#include <Eigen/Core>
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "dyncal/effect_terms.hpp"
#include "dyncal/port.hpp"
#include "dyncal_host/calibration/calibrate.hpp"
#include "dyncal_host/common/model_terms.hpp"

namespace dyncal::host {

/// Per-sample consumer of a stream (the online estimators) and its wrap-up.
struct SampleSink {
  std::function<void(const port::DriveSample&)> push;
  std::function<void(CalibrateResult&)> finish;
};

struct OnlineModel {
  /// Sets up the online path of model built_term_set(i) (KF and RLS from zero with covariance
  /// options.identify.p0, causal differentiator at options.online_cutoff_hz, rows below
  /// options.identify.min_speed_fraction of qd_max [rad/s] left out) behind `sink`.
  /// Throws InputError (cut-off not below half the sample rate).
  using OnlineFn = void (*)(const Eigen::VectorXd& qd_max, const CalibrateOptions& options, SampleSink& sink);
  /// RMS of tau - tau_hat and of tau per joint over `log` through the causal differentiator at
  /// `cutoff` [Hz]; tau_hat = K phi plus the torques of `effects` (a table's effect terms, as the
  /// drive's feed-forward applies them: a coupled motor's coupling term among them). Throws
  /// InputError for an effect term not valid for the robot.
  using VerifyFn = VerificationErrors (*)(const JointLog& log, const std::vector<double>& phi,
                                          const std::vector<EffectTerm>& effects, double cutoff);

  std::array<OnlineFn, kBuiltTermSets> online{};  ///< by built_term_set_index
  std::array<VerifyFn, kBuiltTermSets> verify{};
};

/// Adds (or completes) robot `name`'s online model: entries set in `model` overwrite the registered
/// ones. Called from static initialisers. Returns true.
bool register_online_model(const std::string& name, const OnlineModel& model);

/// The online model of the compiled robot `name`. Throws InputError listing the compiled robots.
const OnlineModel& online_model(const std::string& name);

}  // namespace dyncal::host
