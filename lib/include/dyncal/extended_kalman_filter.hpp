#pragma once

#include <Eigen/Core>

#include "finite.hpp"
#include "nonlinear_friction.hpp"
#include "packed_covariance.hpp"
#include "regressor_structure.hpp"
#include "status.hpp"

namespace dyncal {

/// Extended Kalman filter for the nonlinear model tau = Y_b(q, qd, qdd) phi_b + f(theta, qd)
/// (survey Eq. 13, 20, 21), and with mu < 1 the exponential-forgetting variant (Eq. 24).
/// Parameters phi = [phi_b (Robot::kNumBase) | theta_1 | ... | theta_n], theta_j the
/// NonlinearFriction<M> parameters of joint j (joint-major, kFrictionParams each).
///
/// Each sample linearises f at the current estimate: K = [Y_b  df/dtheta] (df/dtheta block
/// diagonal: joint j's row only), innovation e = tau - Y_b phi_b - f(theta) (Eq. 21), and the
/// block update of PackedCovariance. After the update the friction parameters are projected onto
/// their domain (NonlinearFriction<M>::clamp_parameters, e.g. qds >= 1e-3 rad/s).
/// With mu < 1, P is divided by mu after each sample while trace(P) < trace_max (no wind-up, as in
/// RlsForgetting).
///
/// Memory: PackedCovariance<P> + the N x P regressor; no heap, no exceptions.
template <typename Scalar, class Robot, NonlinearFrictionModel M>
class ExtendedKalmanFilter {
 public:
  using Friction = NonlinearFriction<M>;
  static constexpr int kNumJoints = Robot::kNumJoints;
  static constexpr int kNumBase = Robot::kNumBase;
  static constexpr int kFrictionParams = Friction::kNumParams;
  static constexpr int kNumParams = kNumBase + kNumJoints * kFrictionParams;
  using ParamVector = Eigen::Matrix<Scalar, kNumParams, 1>;
  using JointVector = Eigen::Matrix<Scalar, kNumJoints, 1>;
  using Regressor = Eigen::Matrix<Scalar, kNumJoints, kNumParams>;

  /// Column of friction parameter i (0-based, NonlinearFriction<M>::kNames order) of joint j (0-based).
  static constexpr int column(int i, int joint0) noexcept { return kNumBase + joint0 * kFrictionParams + i; }

  /// Rows where each column of K can be nonzero (generated base structure; friction: own joint).
  static constexpr RegressorStructure<kNumParams> structure() noexcept {
    RegressorStructure<kNumParams> s{};
    set_base_structure<Robot>(s);
    for (int j = 0; j < kNumJoints; ++j) {
      for (int i = 0; i < kFrictionParams; ++i) {
        s.first[column(i, j)] = static_cast<std::int8_t>(j);
        s.last[column(i, j)] = static_cast<std::int8_t>(j);
      }
    }
    return s;
  }

  /// Initial estimate phi0 (its friction part projected onto the domain), initial covariance
  /// diag(p0) > 0, forgetting factor mu in (0, 1] (1: Eq. 21; < 1: Eq. 24), trace_max <= 0 selects
  /// trace(diag(p0)). Errors (nothing changes): rejected_non_finite, invalid_argument.
  UpdateStatus reset(const ParamVector& phi0, const ParamVector& p0, Scalar mu = Scalar(1),
                     Scalar trace_max = Scalar(0)) noexcept {
    if (!all_finite(phi0) || !all_finite(p0)) return UpdateStatus::rejected_non_finite;
    if (!(mu > Scalar(0)) || !(mu <= Scalar(1))) return UpdateStatus::invalid_argument;
    const UpdateStatus s = cov_.reset(p0, structure());
    if (s != UpdateStatus::ok) return s;
    phi_ = phi0;
    for (int j = 0; j < kNumJoints; ++j) Friction::clamp_parameters(phi_.data() + column(0, j));
    mu_ = mu;
    trace_max_ = trace_max > Scalar(0) ? trace_max : p0.sum();
    return UpdateStatus::ok;
  }

  /// Innovation gate in standard deviations (0 disables), as KalmanFilter::set_gate.
  UpdateStatus set_gate(Scalar gate) noexcept {
    if (!(gate >= Scalar(0))) return UpdateStatus::invalid_argument;
    gate_ = gate;
    return UpdateStatus::ok;
  }

  /// One sample: q [rad], qd [rad/s], qdd [rad/s^2], tau [Nm] (joint side), r measurement
  /// variances [Nm^2] > 0. Errors leave the state untouched: rejected_non_finite,
  /// not_positive_definite, rejected_outlier.
  UpdateStatus update(const JointVector& q, const JointVector& qd, const JointVector& qdd, const JointVector& tau,
                      const JointVector& r) noexcept {
    if (!all_finite(q) || !all_finite(qd) || !all_finite(qdd)) return UpdateStatus::rejected_non_finite;
    Robot::base_regressor(q, qd, qdd, K_);
    for (int j = 0; j < kNumJoints; ++j) {
      Scalar jac[kFrictionParams];
      const Scalar f = Friction::torque(phi_.data() + column(0, j), qd[j], jac);
      Scalar jtheta = Scalar(0);
      for (int i = 0; i < kFrictionParams; ++i) {
        jtheta += jac[i] * phi_[column(i, j)];
        for (int k = 0; k < kNumJoints; ++k) K_(k, column(i, j)) = k == j ? jac[i] : Scalar(0);
      }
      y_[j] = tau[j] - f + jtheta;  // so that y - K phi = tau - Y_b phi_b - f(theta)
    }
    const Scalar scale = (mu_ < Scalar(1) && cov_.trace() < trace_max_) ? Scalar(1) / mu_ : Scalar(1);
    const UpdateStatus s = cov_.assimilate(K_, y_, r, gate_, scale, phi_);
    if (s != UpdateStatus::ok) return s;
    for (int j = 0; j < kNumJoints; ++j) Friction::clamp_parameters(phi_.data() + column(0, j));
    return UpdateStatus::ok;
  }

  /// Predicted torque at the current estimate (for residuals and verification).
  void predict(const JointVector& q, const JointVector& qd, const JointVector& qdd, JointVector& tau) noexcept {
    Robot::base_regressor(q, qd, qdd, K_);
    tau = K_.template leftCols<kNumBase>() * phi_.template head<kNumBase>();
    for (int j = 0; j < kNumJoints; ++j)
      tau[j] += Friction::torque(phi_.data() + column(0, j), qd[j], static_cast<Scalar*>(nullptr));
  }

  const ParamVector& estimate() const noexcept { return phi_; }
  const PackedCovariance<Scalar, kNumParams, kNumJoints>& covariance() const noexcept { return cov_; }

 private:
  PackedCovariance<Scalar, kNumParams, kNumJoints> cov_;
  ParamVector phi_ = ParamVector::Zero();
  Regressor K_ = Regressor::Zero();
  JointVector y_ = JointVector::Zero();
  Scalar mu_ = Scalar(1), trace_max_ = Scalar(0), gate_ = Scalar(0);
};

}  // namespace dyncal
