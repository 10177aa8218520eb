// Online (causal) preparation of drive samples for the recursive estimators: low-pass q and tau
// with the same filter (same delay), then q_dot and q_ddot by central differences one sample late.
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "dyncal/finite.hpp"
#include "dyncal/status.hpp"

namespace dyncal {

/// Second-order Butterworth low-pass (bilinear transform, pre-warped) applied per channel to q and
/// tau, and central differences of the filtered q:
///   q_dot[k-1] = (qf[k] - qf[k-2]) / (2 h),  q_ddot[k-1] = (qf[k] - 2 qf[k-1] + qf[k-2]) / h^2,
/// so every output (q, q_dot, q_ddot, tau) refers to sample k-1 and passed through the same filter:
/// the filter's phase lag is common to both sides of tau = K phi ("parallel filtering", Gautier).
/// N channels; h the sample period [s]; cut-off f_c [Hz] < fs / 2. Allocation-free.
template <typename Scalar, int N>
class CausalDifferentiator {
 public:
  using Vec = Eigen::Matrix<Scalar, N, 1>;

  /// Configures the filter; invalid_argument unless 0 < f_c < 1 / (2 h).
  UpdateStatus reset(Scalar h, Scalar f_c) noexcept {
    if (!(h > Scalar(0)) || !(f_c > Scalar(0)) || !(f_c * h < Scalar(0.5))) return UpdateStatus::invalid_argument;
    h_ = h;
    const Scalar k = std::tan(Scalar(3.14159265358979323846) * f_c * h);
    const Scalar norm = Scalar(1) / (Scalar(1) + Scalar(1.41421356237309504880) * k + k * k);
    b0_ = k * k * norm;
    b1_ = Scalar(2) * b0_;
    a1_ = Scalar(2) * (k * k - Scalar(1)) * norm;
    a2_ = (Scalar(1) - Scalar(1.41421356237309504880) * k + k * k) * norm;
    // Outputs wait until the start transient has decayed: 3 / f_c seconds (the filter's step
    // response is within 0.1 % of its final value after about 2.5 / f_c).
    warmup_ = static_cast<long>(std::ceil(Scalar(3) / (f_c * h)));
    count_ = 0;
    return UpdateStatus::ok;
  }

  /// Feeds sample k. Returns ok when (q, qd, qdd, tau) of sample k-1 are ready (after the warm-up
  /// of 3 / f_c seconds), not_ready before, rejected_non_finite for NaN/inf input (state unchanged).
  UpdateStatus update(const Vec& q_in, const Vec& tau_in, Vec& q, Vec& qd, Vec& qdd, Vec& tau) noexcept {
    if (!all_finite(q_in) || !all_finite(tau_in)) return UpdateStatus::rejected_non_finite;
    if (count_ == 0) {  // start the filter in steady state at the first sample
      zq1_ = q_in * (Scalar(1) - b0_);
      zq2_ = q_in * (b0_ - a2_);
      zt1_ = tau_in * (Scalar(1) - b0_);
      zt2_ = tau_in * (b0_ - a2_);
    }
    const Vec qf = filter(q_in, zq1_, zq2_);
    const Vec tf = filter(tau_in, zt1_, zt2_);
    qf2_ = qf1_;
    qf1_ = qf0_;
    qf0_ = qf;
    tf1_ = tf0_;
    tf0_ = tf;
    if (++count_ < warmup_ + 3) return UpdateStatus::not_ready;
    count_ = warmup_ + 3;
    q = qf1_;
    qd = (qf0_ - qf2_) / (Scalar(2) * h_);
    qdd = (qf0_ - Scalar(2) * qf1_ + qf2_) / (h_ * h_);
    tau = tf1_;
    return UpdateStatus::ok;
  }

 private:
  // Transposed direct form II.
  Vec filter(const Vec& x, Vec& z1, Vec& z2) const noexcept {
    const Vec y = b0_ * x + z1;
    z1 = b1_ * x - a1_ * y + z2;
    z2 = b0_ * x - a2_ * y;
    return y;
  }
  Scalar h_ = Scalar(1), b0_ = Scalar(0), b1_ = Scalar(0), a1_ = Scalar(0), a2_ = Scalar(0);
  Vec zq1_ = Vec::Zero(), zq2_ = Vec::Zero(), zt1_ = Vec::Zero(), zt2_ = Vec::Zero();
  Vec qf0_ = Vec::Zero(), qf1_ = Vec::Zero(), qf2_ = Vec::Zero(), tf0_ = Vec::Zero(), tf1_ = Vec::Zero();
  long count_ = 0, warmup_ = 0;
};

}  // namespace dyncal
