// How much of a joint's Coulomb friction the momentum observer's residual may hold because the
// model cannot know its value: at rest and around velocity reversals (docs/monitor.md).
#pragma once

#include <Eigen/Core>
#include <limits>

#include "dyncal/finite.hpp"
#include "dyncal/status.hpp"

namespace dyncal {

/// Per joint a weight w in [0, 1]: the residual may hold up to w |Fc| of friction the model cannot
/// know, so a contact threshold is widened by w |Fc|.
///   w = 1 where the joint rests (its encoder stalled within the velocity's window), where the
///     friction terms' velocity is 0 (inside the standstill band: the true friction is anywhere in
///     [-Fc, Fc], the model's 0) and where that velocity changed sign since the last sample (a
///     reversal: the model's friction flips at the estimated crossing, the true one at the true
///     crossing, and between them they differ by up to 2 Fc; so does a joint that sticks and slips);
///   else w = (1 - K dt) w_prev: the observer forgets a friction error as it forgets any torque,
///     by its own discrete decay (momentum_observer.hpp); below the scalar's epsilon, 0.
/// The standstill band that decides "inside" is the velocity one sample resolves (the host's
/// contact_monitor.hpp: 3.29 times the white-noise std of a backward difference of q), not the
/// window's smoothed slope: a joint whose true velocity may cross 0 within a sample has friction of
/// unknown sign.
/// Units: qd [rad/s], gain K [1/s], dt [s]. N: the most joints (the first `joints` used). No heap.
template <typename Scalar, int N>
class FrictionUncertainty {
 public:
  using Vec = Eigen::Matrix<Scalar, N, 1>;
  using Flags = Eigen::Matrix<int, N, 1>;

  /// K dt in (0, 1], joints 1..N; clears the history (the first sample's weight is 1: unknown).
  /// invalid_argument otherwise (state unchanged).
  UpdateStatus reset(Scalar gain, Scalar dt, int joints) noexcept {
    const Scalar k_dt = gain * dt;
    if (!(k_dt > Scalar(0)) || !(k_dt <= Scalar(1)) || joints < 1 || joints > N) return UpdateStatus::invalid_argument;
    decay_ = Scalar(1) - k_dt;
    joints_ = joints;
    weight_ = Vec::Ones();
    previous_ = Vec::Zero();
    return UpdateStatus::ok;
  }

  /// qd_friction: the friction terms' velocity (0 inside the standstill band); still: 1 where the
  /// joint's encoder stalled within the velocity's window. Writes the weights (entries past
  /// `joints` 0). rejected_non_finite for a NaN or infinite velocity (state unchanged).
  UpdateStatus update(const Vec& qd_friction, const Flags& still, Vec& weight) noexcept {
    if (!all_finite(qd_friction.head(joints_))) return UpdateStatus::rejected_non_finite;
    weight = Vec::Zero();
    for (int j = 0; j < joints_; ++j) {
      const Scalar v = qd_friction[j], p = previous_[j];
      const bool reversal = (v > Scalar(0)) != (p > Scalar(0)) || (v < Scalar(0)) != (p < Scalar(0));
      weight_[j] = still[j] != 0 || v == Scalar(0) || reversal ? Scalar(1) : decay_ * weight_[j];
      if (weight_[j] < std::numeric_limits<Scalar>::epsilon()) weight_[j] = Scalar(0);  // no denormals
      previous_[j] = v;
      weight[j] = weight_[j];
    }
    return UpdateStatus::ok;
  }

 private:
  Vec weight_ = Vec::Ones(), previous_ = Vec::Zero();
  Scalar decay_ = Scalar(0);
  int joints_ = N;
};

}  // namespace dyncal
