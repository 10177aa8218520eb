// Joint velocity for the momentum observer from quantised encoder positions: the slope of the
// least-squares line through 2D + 1 samples centred on the one it reports (docs/monitor.md).
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "dyncal/finite.hpp"
#include "dyncal/status.hpp"

namespace dyncal {

/// The window's half-width D for a momentum observer of gain K [1/s] on samples dt [s] apart:
/// round(1 / (K dt)), at least 1 (the observer's time constant on each side of the sample it
/// takes); capped at 2^30 for a gain near 0.
template <typename Scalar>
int centred_slope_half_width(Scalar gain, Scalar dt) noexcept {
  const double d = std::round(1.0 / (static_cast<double>(gain) * static_cast<double>(dt)));
  return !(d >= 1.0) ? 1 : d > 1073741824.0 ? 1073741824 : static_cast<int>(d);
}

/// How a torque sample relates to the motion between position samples.
///   sampled: the torque at the sample's instant (a logged current, a simulated log's tau(t_m));
///   zero_order: the torque applied from this sample to the next (a drive's own command, held over
///     its control period), so that the motion from q_m to q_{m+1} is tau_m's.
/// The momentum observer (momentum_observer.hpp) integrates the weighted torque by the trapezoidal
/// rule; with the torque's weights below, the change of the slope between samples m - 1 and m
/// equals that integral for either kind: with a held torque the second difference of q at m
/// carries (tau_{m-1} + tau_m) / 2, which shifts the weights half a sample. The other weights leave
/// an acceleration step a residual of up to K dt / 2 of the step (10 % at K dt = 0.2).
enum class TorqueHold : int { sampled = 0, zero_order = 1 };

/// Streams samples (q, tau) and reports, D samples late, sample m's q, its velocity
///   qd_m = sum_{i=-D..D} i q_{m+i} / (dt D (D + 1) (2 D + 1) / 3),
/// the slope of the least-squares line through q_{m-D} .. q_{m+D}, and the torque weighted as
/// that slope weights the acceleration:
///   tau_m = sum_{i=-D..D} w_i tau_{m+i} / sum w_i,   w_i = (D + 1/2)^2 - (i + s)^2,
/// s = 0 for a sampled torque and 1/2 for one held over the period (TorqueHold).
///
/// The slope is symmetric, so q's curvature does not bias it, and the encoder's quantisation,
/// which a difference of neighbouring samples carries whole into qd (sparse impulses of a
/// quantum / dt on a slow joint), is about (2D + 1)^1.5 / 2 times smaller. It is a weighted mean of
/// the velocity over the window, w(s) ~ (D + 1/2)^2 - (s / dt)^2, so its change is the same
/// weighted mean of the acceleration: where the acceleration jumps (a stop or start without a jerk
/// limit) the slope's change lags the torque's by up to half the jump. A momentum observer fed
/// this slope and the raw torque sees M times that lag, low-passed, as a residual (54 false alarms
/// per hour at a stated 0.01 on stop-and-go logs, test_contact_monitor); fed the torque weighted alike,
/// inertial torque and momentum change agree through the step, and the observer's residual is the
/// same weighted mean of the external torque (docs/monitor.md).
///
/// `still` marks a joint whose q did not change on at least one of the window's 2D steps: at or
/// near rest, where friction is static (any value up to its Coulomb level).
///
/// Scalar: float or double. N: the most joints (the first `joints` entries are used, the rest read
/// 0). MaxHalfWidth: the largest D. Memory: two rings of 2 MaxHalfWidth + 1 N-vectors and
/// 2 MaxHalfWidth + 1 weights; no heap.
template <typename Scalar, int N, int MaxHalfWidth = 64>
class CentredSlope {
 public:
  using Vec = Eigen::Matrix<Scalar, N, 1>;
  using Flags = Eigen::Matrix<int, N, 1>;
  static constexpr int kCapacity = 2 * MaxHalfWidth + 1;

  /// Half-width D (samples, 1..MaxHalfWidth), sample period dt [s] > 0, joints 1..N, how the torque
  /// samples relate to the motion (TorqueHold); clears the history. invalid_argument otherwise
  /// (state unchanged).
  UpdateStatus reset(int half_width, Scalar dt, int joints, TorqueHold hold = TorqueHold::sampled) noexcept {
    if (half_width < 1 || half_width > MaxHalfWidth || !(dt > Scalar(0)) || !(dt < Scalar(1e30)) || joints < 1 ||
        joints > N)
      return UpdateStatus::invalid_argument;
    D_ = half_width;
    joints_ = joints;
    norm_ = Scalar(D_ * (D_ + 1) * (2 * D_ + 1)) / Scalar(3) * dt;
    // w_i = (D + 1/2)^2 - (i + s)^2 over i = -D..D, s = 0 for a sampled torque, 1/2 for a held one.
    const double half = D_ + 0.5, shift = hold == TorqueHold::zero_order ? 0.5 : 0.0;
    // Their sum: (2D + 1) ((D + 1/2)^2 - D (D + 1) / 3) for s = 0, 2D (D + 1/2)^2 - D (4 D^2 - 1) / 6
    // (the half-integers' squares) for s = 1/2.
    const double sum = hold == TorqueHold::zero_order ? 2 * D_ * half * half - D_ * (4.0 * D_ * D_ - 1.0) / 6.0
                                                      : (2 * D_ + 1) * (half * half - D_ * (D_ + 1.0) / 3.0);
    for (int i = -D_; i <= D_; ++i) weight_[i + D_] = Scalar((half * half - (i + shift) * (i + shift)) / sum);
    // The least-squares parabola's curvature: qdd = 2 sum (i^2 - c) q_i / (dt^2 sum (i^2 - c)^2),
    // c = D (D + 1) / 3 the mean of i^2 (its columns 1, i, i^2 - c orthogonal on the window).
    double curvature_sum = 0;
    for (int i = -D_; i <= D_; ++i) curvature_sum += (i * i - D_ * (D_ + 1.0) / 3.0) * (i * i - D_ * (D_ + 1.0) / 3.0);
    curvature_norm_ = Scalar(curvature_sum / 2.0 * double(dt) * double(dt));
    count_ = 0;
    stalled_ = Flags::Zero();
    return UpdateStatus::ok;
  }

  int half_width() const noexcept { return D_; }

  /// Feeds one sample (q [rad], tau [Nm]; entries past `joints` ignored). ok: q, qd [rad/s], tau
  /// and still of the sample D before this one are written; not_ready while fewer than 2D + 1
  /// samples are in; rejected_non_finite for a NaN or infinite input (state unchanged).
  UpdateStatus update(const Vec& q_in, const Vec& tau_in, Vec& q, Vec& qd, Vec& tau, Flags& still) noexcept {
    return step(q_in, tau_in, q, qd, nullptr, tau, still);
  }
  /// As above, and qdd [rad/s^2]: twice the curvature of the least-squares parabola through the
  /// window (an acceleration from positions alone, for the direct residual, direct_residual.hpp).
  /// For white position noise sigma its std is about 2 sqrt(45 / (8 D^5)) sigma / dt^2, sqrt(15) /
  /// (D dt) times the slope's: the price of a residual that needs the acceleration.
  UpdateStatus update(const Vec& q_in, const Vec& tau_in, Vec& q, Vec& qd, Vec& qdd, Vec& tau, Flags& still) noexcept {
    return step(q_in, tau_in, q, qd, &qdd, tau, still);
  }

 private:
  UpdateStatus step(const Vec& q_in, const Vec& tau_in, Vec& q, Vec& qd, Vec* qdd, Vec& tau, Flags& still) noexcept {
    if (!all_finite(q_in.head(joints_)) || !all_finite(tau_in.head(joints_))) return UpdateStatus::rejected_non_finite;
    const int window = 2 * D_ + 1;
    // The step this sample adds to the window and the one that leaves it (the window holds 2D steps).
    if (count_ > 0) {
      const Vec& prev = q_ring_[index(count_ - 1)];
      for (int j = 0; j < joints_; ++j) stalled_[j] += q_in[j] == prev[j] ? 1 : 0;
    }
    if (count_ > window - 1) {
      const Vec& a = q_ring_[index(count_ - window)];
      const Vec& b = q_ring_[index(count_ - window + 1)];
      for (int j = 0; j < joints_; ++j) stalled_[j] -= b[j] == a[j] ? 1 : 0;
    }
    q_ring_[index(count_)] = q_in;
    tau_ring_[index(count_)] = tau_in;
    ++count_;
    if (count_ < window) return UpdateStatus::not_ready;
    const long centre = count_ - 1 - D_;
    q = Vec::Zero();
    tau = Vec::Zero();
    qd = Vec::Zero();
    still = Flags::Zero();
    Scalar slope[N] = {};
    for (int i = -D_, k = index(centre - D_); i <= D_; ++i, k = k + 1 == kCapacity ? 0 : k + 1) {
      const Scalar w = weight_[i + D_];
      for (int j = 0; j < joints_; ++j) {
        slope[j] += Scalar(i) * q_ring_[k][j];
        tau[j] += w * tau_ring_[k][j];
      }
    }
    if (qdd) {
      *qdd = Vec::Zero();
      const Scalar mean_square = Scalar(D_ * (D_ + 1)) / Scalar(3);
      for (int i = -D_, k = index(centre - D_); i <= D_; ++i, k = k + 1 == kCapacity ? 0 : k + 1) {
        const Scalar w = Scalar(i * i) - mean_square;
        for (int j = 0; j < joints_; ++j) (*qdd)[j] += w * q_ring_[k][j];
      }
      for (int j = 0; j < joints_; ++j) (*qdd)[j] /= curvature_norm_;
    }
    const int c = index(centre);
    const int n = joints_ < N ? joints_ : N;  // joints_ <= N by reset(); said so for the compiler's bounds check
    for (int j = 0; j < n; ++j) {
      q[j] = q_ring_[c][j];
      qd[j] = slope[j] / norm_;
      still[j] = stalled_[j] > 0 ? 1 : 0;
    }
    if (count_ > 4 * kCapacity) count_ -= 2 * kCapacity;  // keeps the index arithmetic bounded
    return UpdateStatus::ok;
  }

  static int index(long k) noexcept { return static_cast<int>(k % kCapacity); }

  Vec q_ring_[kCapacity] = {};
  Vec tau_ring_[kCapacity] = {};
  Scalar weight_[kCapacity] = {};  ///< w_i / sum w at i + D
  Flags stalled_ = Flags::Zero();
  Scalar norm_ = Scalar(1), curvature_norm_ = Scalar(1);
  long count_ = 0;
  int D_ = 1, joints_ = N;
};

}  // namespace dyncal
