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

/// Streams samples (q, tau) and reports, D samples late, sample m's q and tau with
///   qd_m = sum_{i=-D..D} i q_{m+i} / (dt D (D + 1) (2 D + 1) / 3),
/// the slope of the least-squares line through q_{m-D} .. q_{m+D}: symmetric, so q's curvature
/// does not bias it, and the encoder's quantisation, which a difference of neighbouring samples
/// carries whole into qd (sparse impulses of a quantum / dt on a slow joint), is about
/// (2D + 1)^1.5 / 2 times smaller. Where the acceleration jumps within the window the slope is off
/// by about the jump times D dt / 4.
///
/// `still` marks a joint whose q did not change on at least one of the window's 2D steps: at or
/// near rest, where friction is static (any value up to its Coulomb level).
///
/// Scalar: float or double. N: the most joints (the first `joints` entries are used, the rest read
/// 0). MaxHalfWidth: the largest D. Memory: two rings of 2 MaxHalfWidth + 1 N-vectors; no heap.
template <typename Scalar, int N, int MaxHalfWidth = 64>
class CentredSlope {
 public:
  using Vec = Eigen::Matrix<Scalar, N, 1>;
  using Flags = Eigen::Matrix<int, N, 1>;
  static constexpr int kCapacity = 2 * MaxHalfWidth + 1;

  /// Half-width D (samples, 1..MaxHalfWidth), sample period dt [s] > 0, joints 1..N; clears the
  /// history. invalid_argument otherwise (state unchanged).
  UpdateStatus reset(int half_width, Scalar dt, int joints) noexcept {
    if (half_width < 1 || half_width > MaxHalfWidth || !(dt > Scalar(0)) || !(dt < Scalar(1e30)) || joints < 1 ||
        joints > N)
      return UpdateStatus::invalid_argument;
    D_ = half_width;
    joints_ = joints;
    norm_ = Scalar(D_ * (D_ + 1) * (2 * D_ + 1)) / Scalar(3) * dt;
    count_ = 0;
    stalled_ = Flags::Zero();
    return UpdateStatus::ok;
  }

  int half_width() const noexcept { return D_; }

  /// Feeds one sample (q [rad], tau [Nm]; entries past `joints` ignored). ok: q, qd [rad/s], tau
  /// and still of the sample D before this one are written; not_ready while fewer than 2D + 1
  /// samples are in; rejected_non_finite for a NaN or infinite input (state unchanged).
  UpdateStatus update(const Vec& q_in, const Vec& tau_in, Vec& q, Vec& qd, Vec& tau, Flags& still) noexcept {
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
      for (int j = 0; j < joints_; ++j) slope[j] += Scalar(i) * q_ring_[k][j];
    }
    const int c = index(centre);
    for (int j = 0; j < joints_; ++j) {
      q[j] = q_ring_[c][j];
      tau[j] = tau_ring_[c][j];
      qd[j] = slope[j] / norm_;
      still[j] = stalled_[j] > 0 ? 1 : 0;
    }
    if (count_ > 4 * kCapacity) count_ -= 2 * kCapacity;  // keeps the index arithmetic bounded
    return UpdateStatus::ok;
  }

 private:
  static int index(long k) noexcept { return static_cast<int>(k % kCapacity); }

  Vec q_ring_[kCapacity] = {};
  Vec tau_ring_[kCapacity] = {};
  Flags stalled_ = Flags::Zero();
  Scalar norm_ = Scalar(1);
  long count_ = 0;
  int D_ = 1, joints_ = N;
};

}  // namespace dyncal
