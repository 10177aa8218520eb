#pragma once
// Following a changing parameter (survey Sec. 6.2, Fig. 4, Table 2's last row): the viscous
// coefficient beta of one joint changes with the sample count N while the recursive Eq. 7 methods
// (Kalman filter Eq. 19, exponential forgetting Eq. 23, the lib/ updaters) run over the samples.

#include <string>
#include <vector>

#include "dyncal_host/survey/methods/methods.hpp"
#include "dyncal_host/survey/survey_data.hpp"

namespace dyncal::host::survey {

/// How beta changes over the run of S samples: from beta0 to 1.5 beta0, starting at N = S / 2:
/// step (at once), ramp (slope change: linearly until N = S), second order (quadratically).
enum class ChangeProfile { step, ramp, second_order };
const char* to_string(ChangeProfile p);

struct TrackingResult {
  std::string method;
  ChangeProfile profile = ChangeProfile::step;
  /// Over the last quarter of the run (N >= 3 S / 4: a step's transient has decayed, a ramp's lag
  /// has settled), relative to the change 0.5 beta0: the lag |mean(beta_hat - beta)| (what tracking
  /// is about), the scatter std(beta_hat - beta) (the noise the memory lets through), and the
  /// mean |beta_hat - beta| (both).
  double relative_lag = 0, relative_scatter = 0, relative_error = 0;
  std::vector<double> beta, beta_hat;  ///< per sample [Nm s/rad]
};

/// The recorded states of `d` with the torque the plant needs to follow them when joint `joint`'s
/// (1-based) beta follows `profile`: tau + (beta(N) - beta0) qd_j. On an Eq. 7 run: the Kalman filter
/// (R = sigma^2, Eq. 19) and exponential forgetting (Eq. 23) with factor `mu`; on an Eq. 4 run: the
/// extended Kalman filter (Eq. 21) and its forgetting form (Eq. 24, `mu`). One result each.
std::vector<TrackingResult> track_viscous_friction(const SurveyData& d, const MethodSettings& settings,
                                                   ChangeProfile profile, int joint, double mu);

inline constexpr const char* kConsistentForgetting = "physically consistent LS + forgetting";

/// dyncal's hybrid kConsistentForgetting: a drive calibrated offline by
/// physically consistent LS (`calibration`, any friction model) keeps its rigid-body part, consistent
/// by construction, and its friction's scale parameters, and tracks the friction amplitudes (every
/// friction parameter but the scale parameters: Eq. 7 Fc, beta; Eq. 4 Fc, Fs, beta) of all joints
/// online: lib/ RlsForgetting (Eq. 23, factor `mu`, weights 1/sigma, start: the calibration's
/// amplitudes with covariance p0) on tau - Y_b phi_b - the friction no amplitude multiplies. The
/// survey's premise (Sec. 3.3): inertial parameters are fixed, friction changes with temperature
/// and time. Run on `d` as track_viscous_friction (joint `joint`'s beta following `profile`); the
/// result is named kConsistentForgetting, with " (Eq. N)" on a model other than Eq. 7.
/// Throws InputError on a calibration of the wrong size or a joint outside 1..6.
TrackingResult track_friction_after_calibration(const SurveyData& d, const Estimate& calibration,
                                                const MethodSettings& settings, ChangeProfile profile, int joint,
                                                double mu);

/// Table 2: 'A' follows a slope change, 'B' a step change only, 'C' neither. Follows: relative lag
/// below 0.2 (Table 2's level-A bound on relative parameter errors).
char follow_level(double ramp_relative_lag, double step_relative_lag);

}  // namespace dyncal::host::survey
