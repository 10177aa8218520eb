#pragma once
// Following a changing parameter (survey Sec. 6.2, Fig. 4, Table 2's last row): the viscous
// coefficient beta of one joint changes with the sample count N while the recursive Eq. 7 methods
// (Kalman filter Eq. 19, exponential forgetting Eq. 23, the lib/ updaters) run over the samples.

#include <string>
#include <vector>

#include "dyncal_host/survey/methods.hpp"

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

/// Table 2: 'A' follows a slope change, 'B' a step change only, 'C' neither. Follows: relative lag
/// below 0.2 (Table 2's level-A bound on relative parameter errors).
char follow_level(double ramp_relative_lag, double step_relative_lag);

}  // namespace dyncal::host::survey
