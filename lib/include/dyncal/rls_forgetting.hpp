#pragma once

#include <Eigen/Core>

#include "finite.hpp"
#include "packed_covariance.hpp"
#include "regressor_structure.hpp"
#include "status.hpp"
#include "ud_covariance.hpp"

namespace dyncal {

/// Recursive least squares with exponential forgetting factor mu (survey Eq. 22-23):
/// minimises sum_i mu^(n-i) |W (tau_i - K_i phi)|^2, with
///   G = P K^T (K P K^T + mu W^-2)^-1,  phi += G (tau - K phi),  P = (I - G K) P / mu.
/// W = diag(w) weights each joint (w = 1 reproduces Eq. 23). The N rows of a sample are folded in
/// one block update on packed symmetric P (PackedCovariance), the division by mu included. For
/// the nonlinear model (Eq. 24) pass the linearised K and y as for the EKF.
///
/// Covariance wind-up: while the data do not excite some direction, dividing by mu makes P grow
/// without bound in it. Forgetting is skipped for a sample whenever trace(P) already exceeds
/// `trace_max` (set by reset(); default: the trace of the initial P), which bounds P.
///
/// Covariance: PackedCovariance (default) or UdCovariance<Scalar, P>, as for KalmanFilter.
///
/// Size: P fixed, or P = Eigen::Dynamic with a PackedCovariance of capacity MaxP, as for KalmanFilter.
///
/// Memory (packed): P(P+1)/2 + (N + 2) P scalars (MaxP for the run-time size); no heap, no exceptions.
template <typename Scalar, int P, int N, class Covariance = PackedCovariance<Scalar, P, N>>
class RlsForgetting {
 public:
  using ParamVector = ParamVectorOf<Scalar, P, Covariance::kCapacity>;
  using MeasVector = Eigen::Matrix<Scalar, N, 1>;
  using Regressor = RegressorOf<Scalar, N, P, Covariance::kCapacity>;
  using Structure = RegressorStructure<Covariance::kCapacity>;

  /// mu in (0, 1]; p0 > 0 (initial covariance diag(p0)); trace_max <= 0 selects trace(diag(p0));
  /// structure of K (default dense). invalid_argument (also: phi0 and p0 of different or
  /// unsupported run-time sizes) / rejected_non_finite leave the filter unchanged.
  UpdateStatus reset(const ParamVector& phi0, const ParamVector& p0, Scalar mu, Scalar trace_max = Scalar(0),
                     const Structure& structure = Structure::dense(N)) noexcept {
    if (phi0.size() != p0.size()) return UpdateStatus::invalid_argument;  // the run-time size only
    if (!all_finite(phi0) || !all_finite(p0)) return UpdateStatus::rejected_non_finite;
    if (!(mu > Scalar(0)) || !(mu <= Scalar(1))) return UpdateStatus::invalid_argument;
    const UpdateStatus s = cov_.template reset<N>(p0, structure);
    if (s != UpdateStatus::ok) return s;
    phi_ = phi0;
    mu_ = mu;
    trace_max_ = trace_max > Scalar(0) ? trace_max : p0.sum();
    return UpdateStatus::ok;
  }

  /// One sample: K (N x P), tau (N) [Nm], w (N) joint weights > 0 (1/sigma_j, or ones).
  /// Errors leave the state untouched: rejected_non_finite, invalid_argument (w <= 0, or K nonzero
  /// outside its structure), not_positive_definite.
  UpdateStatus update(const Regressor& K, const MeasVector& tau, const MeasVector& w) noexcept {
    for (int j = 0; j < N; ++j) {
      if (!std::isfinite(w[j])) return UpdateStatus::rejected_non_finite;
      if (!(w[j] > Scalar(0))) return UpdateStatus::invalid_argument;
      r_[j] = mu_ / (w[j] * w[j]);
    }
    const Scalar scale = cov_.trace() < trace_max_ ? Scalar(1) / mu_ : Scalar(1);
    return cov_.assimilate(K, tau, r_, Scalar(0), scale, phi_);
  }

  /// Unit weights (survey Eq. 23 as printed).
  UpdateStatus update(const Regressor& K, const MeasVector& tau) noexcept { return update(K, tau, MeasVector::Ones()); }

  const ParamVector& estimate() const noexcept { return phi_; }
  const Covariance& covariance() const noexcept { return cov_; }
  Scalar mu() const noexcept { return mu_; }

 private:
  Covariance cov_;
  ParamVector phi_ = initial_params<ParamVector>();
  MeasVector r_ = MeasVector::Ones();
  Scalar mu_ = Scalar(1);
  Scalar trace_max_ = Scalar(0);
};

}  // namespace dyncal
