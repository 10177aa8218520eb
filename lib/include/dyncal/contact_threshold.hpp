#pragma once

#include <cmath>

namespace dyncal {

/// P(X <= u < Y) for a standard bivariate normal (X, Y) with correlation rho in (-1, 1): the
/// probability that a stationary Gaussian sequence of unit variance and lag-1 correlation rho
/// crosses the level u upwards between two samples. By Simpson's rule on
/// integral_{-inf}^{u} phi(x) Q((u - rho x) / sqrt(1 - rho^2)) dx over where the integrand is not
/// negligible (below 1e-30 of its scale).
template <typename Scalar>
Scalar upcrossing_probability(Scalar u, Scalar rho) noexcept {
  using std::erfc;
  using std::exp;
  using std::sqrt;
  const Scalar spread = sqrt(Scalar(1) - rho * rho);
  Scalar lo = u - Scalar(12);
  if (rho > Scalar(0)) {
    const Scalar near = (u - Scalar(12) * spread) / rho;  // beyond it Q(...) is below 1e-33
    if (near > lo) lo = near;
  }
  if (!(lo < u)) return Scalar(0);
  constexpr int kIntervals = 400;  // even
  const Scalar h = (u - lo) / Scalar(kIntervals);
  const Scalar inv_sqrt_2pi = Scalar(0.398942280401432677939946);
  const Scalar inv_sqrt2 = Scalar(0.707106781186547524400844);
  Scalar sum = Scalar(0);
  for (int i = 0; i <= kIntervals; ++i) {
    const Scalar x = lo + h * Scalar(i);
    const Scalar f = inv_sqrt_2pi * exp(-x * x / Scalar(2)) * Scalar(0.5) * erfc((u - rho * x) / spread * inv_sqrt2);
    sum += (i == 0 || i == kIntervals ? Scalar(1) : (i % 2 == 1 ? Scalar(4) : Scalar(2))) * f;
  }
  return sum * h / Scalar(3);
}

/// The contact threshold of one joint's residual r (momentum_observer.hpp) for a stated false-alarm
/// rate, from the residual's statistics on contact-free motion (docs/monitor.md "Thresholds"): an
/// alarm when |r - mean| > c, mean the residual's mean on that motion (the model's bias on the
/// joint). s: the residual's standard deviation [Nm], s_d: the standard deviation of its
/// sample-to-sample difference [Nm], dt the sample period [s], `joints` J the joints that share the
/// rate, alarms_per_second alpha what the whole arm may raise.
///
/// Returns c = s u [Nm] with 2 P(X <= u < Y) = alpha dt / J, (X, Y) consecutive samples of the
/// standardised residual: a crossing of the band, either sign, has probability alpha dt / J per
/// sample and joint. For a stationary Gaussian sequence that probability depends only on the lag-1
/// correlation rho = 1 - s_d^2 / (2 s^2) (the expected number of up-crossings per sample, exactly:
/// the discrete form of Rice's formula), which upcrossing_probability computes; u by 40 bisections
/// on [0, 40]. Where even u = 0 crosses less often, 0. NaN for s or s_d not > 0 or not finite, dt or
/// alpha not > 0, J < 1: no threshold without statistics.
template <typename Scalar>
Scalar contact_threshold(Scalar s, Scalar s_d, Scalar dt, int joints, Scalar alarms_per_second) noexcept {
  if (!(s > Scalar(0)) || !(s_d > Scalar(0)) || !(dt > Scalar(0)) || joints < 1 || !(alarms_per_second > Scalar(0)) ||
      !std::isfinite(s) || !std::isfinite(s_d))
    return Scalar(NAN);
  Scalar rho = Scalar(1) - s_d * s_d / (Scalar(2) * s * s);
  if (rho < Scalar(-0.999999)) rho = Scalar(-0.999999);
  if (rho > Scalar(0.999999)) rho = Scalar(0.999999);
  const Scalar target = alarms_per_second * dt / Scalar(2 * joints);  // per sample, per sign
  Scalar lo = Scalar(0), hi = Scalar(40);
  if (upcrossing_probability(lo, rho) <= target) return Scalar(0);
  for (int i = 0; i < 40; ++i) {  // 40 / 2^40: below either scalar's resolution
    const Scalar mid = Scalar(0.5) * (lo + hi);
    (upcrossing_probability(mid, rho) > target ? lo : hi) = mid;
  }
  return s * hi;
}

}  // namespace dyncal
