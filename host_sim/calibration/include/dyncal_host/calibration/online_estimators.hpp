#pragma once
// calibrate's online path and its verification, for any compiled robot: lib/ KF and RLS with
// forgetting at the model's run-time size (recursive_fit.hpp) fed sample by sample through lib/'s
// causal differentiator, and the error of a parameter vector on a fresh log. Compiled once per
// joint count; the robot enters through its TermSetModel's regressor.

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "dyncal/effect_terms.hpp"
#include "dyncal/port.hpp"
#include "dyncal_host/calibration/calibrate_options.hpp"
#include "dyncal_host/calibration/calibrate_result.hpp"
#include "dyncal_host/model/term_set_model.hpp"

namespace dyncal::host {

/// Per-sample consumer of a stream (the online estimators) and its wrap-up.
struct SampleSink {
  std::function<void(const port::DriveSample&)> push;
  std::function<void(CalibrateResult&)> finish;
};

/// Sets up the online path of `model` behind `sink`: KF and RLS from zero with covariance
/// options.identify.p0 (RLS forgetting factor options.rls_mu), the causal differentiator at
/// options.online_cutoff_hz, rows below options.identify.min_speed_fraction of qd_max [rad/s, N]
/// left out. finish() writes phi_kf, phi_rls (P) and the update counts. Throws InputError (cut-off
/// not below half the sample rate; p0 or mu refused by the filters).
void start_online_estimators(const TermSetModel& model, const Eigen::VectorXd& qd_max, const CalibrateOptions& options,
                             SampleSink& sink);

/// RMS of tau - tau_hat and of tau per joint over `log` (N joints) through the causal
/// differentiator at `cutoff` [Hz]; tau_hat = K phi (K: model's regressor, phi: P) plus the torques
/// of `effects` (a table's effect terms, as the drive's feed-forward applies them: a coupled
/// motor's coupling term among them). Throws InputError for an effect term not valid for the robot.
VerificationErrors verify_parameters(const TermSetModel& model, const JointLog& log, const std::vector<double>& phi,
                                     const std::vector<EffectTerm>& effects, double cutoff);

}  // namespace dyncal::host
