#pragma once

#include <Eigen/Core>
#include <cmath>

#include "finite.hpp"
#include "status.hpp"
#include "ud_covariance.hpp"

namespace dyncal {

/// Kalman filter for constant parameters (survey Eq. 19): phi_n = phi_{n-1} + G (tau - K phi),
/// P_n = (I - G K) P_{n-1}, with measurement noise R = diag(r) (variance per joint [Nm^2]).
/// The N measurements of a sample are processed as N sequential scalar updates (exact for a
/// diagonal R) on a UD-factorised covariance (Bierman), which keeps P symmetric positive definite
/// in float.
///
/// Optional innovation gating: with gate > 0 a sample any of whose innovations exceeds
/// gate * sqrt(innovation variance) under the prior is rejected (rejected_outlier) before any
/// change. A gate of 0 disables gating.
///
/// Memory: UdCovariance<P> + 3P scalars; no heap, no exceptions.
template <typename Scalar, int P, int N>
class KalmanFilter {
 public:
  using ParamVector = Eigen::Matrix<Scalar, P, 1>;
  using MeasVector = Eigen::Matrix<Scalar, N, 1>;
  using Regressor = Eigen::Matrix<Scalar, N, P>;

  /// Initial estimate phi0 and initial covariance diag(p0) (all > 0).
  UpdateStatus reset(const ParamVector& phi0, const ParamVector& p0) noexcept {
    if (!all_finite(phi0) || !all_finite(p0)) return UpdateStatus::rejected_non_finite;
    const UpdateStatus s = cov_.reset(p0);
    if (s != UpdateStatus::ok) return s;
    phi_ = phi0;
    return UpdateStatus::ok;
  }

  /// Innovation gate in standard deviations (0 disables; negative is invalid_argument).
  UpdateStatus set_gate(Scalar gate) noexcept {
    if (!(gate >= Scalar(0))) return UpdateStatus::invalid_argument;
    gate_ = gate;
    return UpdateStatus::ok;
  }

  /// One sample: K (N x P), tau (N) [Nm], r (N) measurement variances [Nm^2], all r > 0.
  /// Errors leave the state untouched: rejected_non_finite, not_positive_definite (r <= 0 or a
  /// numerically indefinite update), rejected_outlier (gating).
  UpdateStatus update(const Regressor& K, const MeasVector& tau, const MeasVector& r) noexcept {
    if (!all_finite(K) || !all_finite(tau) || !all_finite(r)) return UpdateStatus::rejected_non_finite;
    for (int j = 0; j < N; ++j) {
      if (!(r[j] > Scalar(0))) return UpdateStatus::not_positive_definite;
    }
    if (gate_ > Scalar(0)) {
      for (int j = 0; j < N; ++j) {
        h_ = K.row(j).transpose();
        const Scalar e = tau[j] - h_.dot(phi_);
        const Scalar s = cov_.innovation_variance(h_, r[j]);
        if (e * e > gate_ * gate_ * s) return UpdateStatus::rejected_outlier;
      }
    }
    for (int j = 0; j < N; ++j) {
      h_ = K.row(j).transpose();
      // Cannot fail for r > 0, finite inputs and a positive D; a failure here (overflow) would
      // leave the rows before it applied, and is reported.
      const UpdateStatus s = cov_.assimilate(h_, tau[j], r[j], phi_);
      if (s != UpdateStatus::ok) return s;
    }
    return UpdateStatus::ok;
  }

  const ParamVector& estimate() const noexcept { return phi_; }
  const UdCovariance<Scalar, P>& covariance() const noexcept { return cov_; }

 private:
  UdCovariance<Scalar, P> cov_;
  ParamVector phi_ = ParamVector::Zero();
  ParamVector h_;
  Scalar gate_ = Scalar(0);
};

}  // namespace dyncal
