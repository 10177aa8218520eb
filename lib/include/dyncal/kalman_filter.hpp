#pragma once

#include <Eigen/Core>

#include "finite.hpp"
#include "packed_covariance.hpp"
#include "regressor_structure.hpp"
#include "status.hpp"
#include "ud_covariance.hpp"

namespace dyncal {

/// Kalman filter for constant parameters (survey Eq. 19): phi_n = phi_{n-1} + G (tau - K phi),
/// G = P K^T (K P K^T + R)^-1, P_n = (I - G K) P_{n-1}, with measurement noise R = diag(r)
/// (variance per joint [Nm^2]). For the nonlinear friction models (survey Eq. 21) pass the
/// linearised K = [K_d  df/dphi_f] and y = tau - f(phi_f) + (df/dphi_f) phi_f, which makes this
/// the extended Kalman filter (dyncal/extended_kalman_filter.hpp does that).
///
/// P is kept in packed symmetric storage and the N measurements of a sample are folded in one
/// block update (PackedCovariance); with the regressor's structure (IdentificationModel::
/// structure()) the update skips its structural zeros.
///
/// Optional innovation gating: with gate > 0 a sample any of whose innovations exceeds
/// gate * sqrt(innovation variance) under the prior is rejected (rejected_outlier) before any
/// change. A gate of 0 disables gating. For Gaussian noise a gate g rejects a good sample with
/// probability about N * erfc(g / sqrt(2)) (g = 5: 3.4e-6 for N = 6).
///
/// Covariance: PackedCovariance (default; fast, uses K's structure) or UdCovariance<Scalar, P>
/// (Bierman UD factors; slower, but holds variance ranges beyond float's precision — see there).
///
/// Size: P fixed, or P = Eigen::Dynamic with Covariance = PackedCovariance<Scalar, Eigen::Dynamic,
/// N, MaxP>: then reset() sets the size to phi0's (1..MaxP), and the vectors and K are Eigen's
/// fixed-capacity dynamic matrices (the host's KF for any robot; the arithmetic is the same).
///
/// Memory (packed): P(P+1)/2 + (N + 2) P scalars (MaxP for the run-time size); no heap, no exceptions.
template <typename Scalar, int P, int N, class Covariance = PackedCovariance<Scalar, P, N>>
class KalmanFilter {
 public:
  using ParamVector = ParamVectorOf<Scalar, P, Covariance::kCapacity>;
  using MeasVector = Eigen::Matrix<Scalar, N, 1>;
  using Regressor = RegressorOf<Scalar, N, P, Covariance::kCapacity>;
  using Structure = RegressorStructure<Covariance::kCapacity>;

  /// Initial estimate phi0, initial covariance diag(p0) (all > 0) and the structure of K
  /// (default: dense). invalid_argument (also: phi0 and p0 of different or unsupported run-time
  /// sizes) / rejected_non_finite leave the filter unchanged.
  UpdateStatus reset(const ParamVector& phi0, const ParamVector& p0,
                     const Structure& structure = Structure::dense(N)) noexcept {
    if (phi0.size() != p0.size()) return UpdateStatus::invalid_argument;  // the run-time size only
    if (!all_finite(phi0) || !all_finite(p0)) return UpdateStatus::rejected_non_finite;
    const UpdateStatus s = cov_.template reset<N>(p0, structure);
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
  /// numerically indefinite update), rejected_outlier (gating), invalid_argument (K nonzero
  /// outside the structure given to reset()).
  UpdateStatus update(const Regressor& K, const MeasVector& tau, const MeasVector& r) noexcept {
    return cov_.assimilate(K, tau, r, gate_, Scalar(1), phi_);
  }

  const ParamVector& estimate() const noexcept { return phi_; }
  const Covariance& covariance() const noexcept { return cov_; }

 private:
  Covariance cov_;
  ParamVector phi_ = initial_params<ParamVector>();
  Scalar gate_ = Scalar(0);
};

}  // namespace dyncal
