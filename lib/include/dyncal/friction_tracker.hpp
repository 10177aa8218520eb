#pragma once

#include <Eigen/Core>

#include "finite.hpp"
#include "friction.hpp"
#include "nonlinear_friction.hpp"
#include "rls_forgetting.hpp"
#include "status.hpp"

namespace dyncal {

/// One joint's friction as amplitudes times columns: the amplitudes are the parameters the torque
/// is linear in; the columns depend on qd [rad/s], tau_load [Nm] (Eq. 9) and the model's scale
/// parameters, which stay fixed. Interface used by FrictionTracker:
///   kNumParams            parameters per joint (the model's order)
///   kNumAmplitudes        how many of them are amplitudes
///   amplitude(i)          index of amplitude i among the parameters
///   columns(theta, qd, tau_load, out)  d tau_f / d amplitude (kNumAmplitudes), which does not
///                         depend on the amplitudes; theta: the joint's kNumParams parameters.
///
/// A linear term set (survey Eq. 7, 8, 9: kFrictionEq7/8/9): every parameter is an amplitude, the
/// columns are term_column of each term in the fixed order (Fc, Fv, Fp, Fl).
template <unsigned Terms>
struct LinearFrictionAmplitudes {
  static_assert((Terms & ~(term::coulomb | term::viscous | term::power | term::load)) == 0u,
                "friction terms only (no rotor inertia or offset)");
  static constexpr int count() noexcept {
    int n = 0;
    for (int i = 0; i < kNumTerms; ++i) n += (Terms & term_bit(i)) != 0u;
    return n;
  }
  static constexpr int kNumParams = count();
  static constexpr int kNumAmplitudes = kNumParams;
  static constexpr int amplitude(int i) noexcept { return i; }
  template <typename Scalar>
  static void columns(const Scalar* /*theta*/, Scalar qd, Scalar tau_load, Scalar* out) noexcept {
    int k = 0;
    for (int i = 0; i < kNumTerms; ++i) {
      if ((Terms & term_bit(i)) != 0u) out[k++] = term_column(term_bit(i), qd, Scalar(0), tau_load);
    }
  }
};

/// A nonlinear model (survey Eq. 4, 5, 6) at fixed scale parameters (NonlinearFriction<M>::
/// kIsScale: qds of Eq. 4; f3, f5 of Eq. 5; f3, f4 of Eq. 6): the amplitudes are the others, their
/// columns the Jacobian entries of NonlinearFriction<M>::torque.
template <NonlinearFrictionModel M>
struct NonlinearFrictionAmplitudes {
  using Friction = NonlinearFriction<M>;
  static constexpr int kNumParams = Friction::kNumParams;
  static constexpr int count() noexcept {
    int n = 0;
    for (int i = 0; i < kNumParams; ++i) n += !Friction::kIsScale[i];
    return n;
  }
  static constexpr int kNumAmplitudes = count();
  static constexpr int amplitude(int i) noexcept {
    for (int k = 0; k < kNumParams; ++k) {
      if (!Friction::kIsScale[k] && i-- == 0) return k;
    }
    return -1;
  }
  template <typename Scalar>
  static void columns(const Scalar* theta, Scalar qd, Scalar /*tau_load*/, Scalar* out) noexcept {
    Scalar jac[kNumParams];
    (void)Friction::torque(theta, qd, jac);
    for (int i = 0; i < kNumAmplitudes; ++i) out[i] = jac[amplitude(i)];
  }
};

/// Online tracking of the friction of N joints on a calibrated drive: the rigid-body part and the
/// friction's scale parameters stay at their calibrated values (e.g. physically consistent least
/// squares: inertial parameters are fixed, friction drifts with temperature and wear, survey
/// Sec. 3.3), the amplitudes of every joint follow by recursive least squares with exponential
/// forgetting (survey Eq. 23, factor mu) on
///   tau_friction = tau - Y_b(q, qd, qdd) phi_b   [Nm] (the caller's calibrated rigid-body torque).
/// Joints are independent (joint j's amplitudes act on its own torque only): one RlsForgetting of
/// kNumAmplitudes parameters per joint, each with its own covariance wind-up bound.
///
/// Friction: LinearFrictionAmplitudes<Terms> or NonlinearFrictionAmplitudes<M>.
/// Memory: N small filters, their backups and the parameters; no heap, no exceptions.
template <typename Scalar, int N, class Friction>
class FrictionTracker {
 public:
  static constexpr int kNumParams = Friction::kNumParams;
  static constexpr int kNumAmplitudes = Friction::kNumAmplitudes;
  using JointVector = Eigen::Matrix<Scalar, N, 1>;
  /// Parameters of all joints, joint-major (joint j's kNumParams in the model's order).
  using ParamVector = Eigen::Matrix<Scalar, N * kNumParams, 1>;

  /// theta0: calibrated parameters (scale parameters kept from here on); p0 > 0: initial variance
  /// of every amplitude (in (Nm / w)^2 units of the weights given to update); mu in (0, 1].
  /// Errors (nothing changes): rejected_non_finite, invalid_argument.
  UpdateStatus reset(const ParamVector& theta0, Scalar p0, Scalar mu) noexcept {
    if (!all_finite(theta0) || !std::isfinite(p0)) return UpdateStatus::rejected_non_finite;
    if (!(p0 > Scalar(0)) || !(mu > Scalar(0)) || !(mu <= Scalar(1))) return UpdateStatus::invalid_argument;
    for (int j = 0; j < N; ++j) {
      AmplitudeVector a;
      for (int i = 0; i < kNumAmplitudes; ++i) a[i] = theta0[kNumParams * j + Friction::amplitude(i)];
      const UpdateStatus s = rls_[j].reset(a, AmplitudeVector::Constant(p0), mu);
      if (s != UpdateStatus::ok) return s;  // not reached: inputs checked above
    }
    theta_ = theta0;
    return UpdateStatus::ok;
  }

  /// One sample: qd [rad/s], tau_load [Nm] (read by the load term of Eq. 9 only), tau_friction
  /// [Nm] as above, w > 0 joint weights (1 / sigma_j, or ones). Errors leave every joint's state
  /// untouched: rejected_non_finite, invalid_argument (w <= 0), not_positive_definite.
  UpdateStatus update(const JointVector& qd, const JointVector& tau_load, const JointVector& tau_friction,
                      const JointVector& w) noexcept {
    if (!all_finite(qd) || !all_finite(tau_load) || !all_finite(tau_friction) || !all_finite(w)) {
      return UpdateStatus::rejected_non_finite;
    }
    for (int j = 0; j < N; ++j) {
      if (!(w[j] > Scalar(0))) return UpdateStatus::invalid_argument;
    }
    for (int j = 0; j < N; ++j) backup_[j] = rls_[j];
    for (int j = 0; j < N; ++j) {
      Friction::columns(theta_.data() + kNumParams * j, qd[j], tau_load[j], K_.data());
      const UpdateStatus s = rls_[j].update(K_, tau_friction.template segment<1>(j), w.template segment<1>(j));
      if (s != UpdateStatus::ok) {
        for (int k = 0; k < j; ++k) rls_[k] = backup_[k];
        return s;
      }
    }
    for (int j = 0; j < N; ++j) {
      for (int i = 0; i < kNumAmplitudes; ++i) theta_[kNumParams * j + Friction::amplitude(i)] = rls_[j].estimate()[i];
    }
    return UpdateStatus::ok;
  }

  /// Current parameters, joint-major; the amplitudes tracked, the scale parameters as calibrated.
  const ParamVector& parameters() const noexcept { return theta_; }

  /// Friction torque of joint j (0-based) at qd with the current parameters [Nm] (every model here
  /// is homogeneous in its amplitudes: columns times amplitudes).
  Scalar torque(int j, Scalar qd, Scalar tau_load) const noexcept {
    Scalar c[kNumAmplitudes];
    Friction::columns(theta_.data() + kNumParams * j, qd, tau_load, c);
    Scalar t = Scalar(0);
    for (int i = 0; i < kNumAmplitudes; ++i) t += c[i] * theta_[kNumParams * j + Friction::amplitude(i)];
    return t;
  }

 private:
  using Filter = RlsForgetting<Scalar, kNumAmplitudes, 1>;
  using AmplitudeVector = typename Filter::ParamVector;
  Filter rls_[N];
  Filter backup_[N];
  typename Filter::Regressor K_ = Filter::Regressor::Zero();
  ParamVector theta_ = ParamVector::Zero();
};

}  // namespace dyncal
