#pragma once

#include <cmath>

namespace dyncal {

/// The survey's nonlinear friction models of one joint (Eq. 4, 5, 6), tau_f = f(theta, qd), with
/// the analytic Jacobian d tau_f / d theta used by the EKF (Eq. 21) and forgetting (Eq. 24).
/// qd [rad/s], tau_f [Nm]. sgn(0) = 0. Allocation-free; the functions are total: parameters
/// outside their domain are first projected onto it (clamp_parameters), as the EKF does after each
/// update.
enum class NonlinearFrictionModel { eq4, eq5, eq6 };

template <NonlinearFrictionModel M>
struct NonlinearFriction;

/// Survey Eq. 4 (Stribeck curve of the LuGre model in steady state):
///   tau_f = [Fc + (Fs - Fc) exp(-|qd / qds|^delta_s)] sgn(qd) + beta qd,
/// theta = (Fc [Nm], Fs [Nm], qds [rad/s] > 0, beta [Nm s/rad]); delta_s fixed (default 2).
template <>
struct NonlinearFriction<NonlinearFrictionModel::eq4> {
  static constexpr int kNumParams = 4;
  static constexpr const char* kNames[kNumParams] = {"Fc", "Fs", "qds", "beta"};
  /// Scale parameters (a velocity or an inverse velocity); the torque is linear in the others.
  static constexpr bool kIsScale[kNumParams] = {false, false, true, false};
  template <typename Scalar>
  static void clamp_parameters(Scalar* theta) noexcept {
    if (!(theta[2] > Scalar(1e-3))) theta[2] = Scalar(1e-3);
  }
  /// tau_f and, when jac != nullptr, d tau_f / d theta (kNumParams).
  template <typename Scalar>
  static Scalar torque(const Scalar* theta, Scalar qd, Scalar* jac, Scalar delta_s = Scalar(2)) noexcept {
    using std::abs;
    using std::exp;
    using std::pow;
    const Scalar sg = qd > Scalar(0) ? Scalar(1) : (qd < Scalar(0) ? Scalar(-1) : Scalar(0));
    const Scalar qds = theta[2] > Scalar(1e-3) ? theta[2] : Scalar(1e-3);
    const Scalar x = abs(qd) / qds;
    const Scalar xd = delta_s == Scalar(2) ? x * x : pow(x, delta_s);
    const Scalar E = exp(-xd);
    if (jac != nullptr) {
      jac[0] = (Scalar(1) - E) * sg;
      jac[1] = E * sg;
      jac[2] = (theta[1] - theta[0]) * sg * E * delta_s * xd / qds;
      jac[3] = qd;
    }
    return (theta[0] + (theta[1] - theta[0]) * E) * sg + theta[3] * qd;
  }
};

/// Survey Eq. 5: tau_f = f1 sgn(qd) - f2 sgn(qd) exp(-|qd| / f3) - f4 sgn(qd) exp(-1 / (f5 |qd|))
/// + beta qd, theta = (f1 [Nm], f2 [Nm], f3 [rad/s] > 0, f4 [Nm], f5 [s/rad] > 0, beta [Nm s/rad]).
template <>
struct NonlinearFriction<NonlinearFrictionModel::eq5> {
  static constexpr int kNumParams = 6;
  static constexpr const char* kNames[kNumParams] = {"f1", "f2", "f3", "f4", "f5", "beta"};
  static constexpr bool kIsScale[kNumParams] = {false, false, true, false, true, false};
  template <typename Scalar>
  static void clamp_parameters(Scalar* theta) noexcept {
    if (!(theta[2] > Scalar(1e-3))) theta[2] = Scalar(1e-3);
    if (!(theta[4] > Scalar(1e-3))) theta[4] = Scalar(1e-3);
  }
  template <typename Scalar>
  static Scalar torque(const Scalar* theta, Scalar qd, Scalar* jac) noexcept {
    using std::abs;
    using std::exp;
    const Scalar sg = qd > Scalar(0) ? Scalar(1) : (qd < Scalar(0) ? Scalar(-1) : Scalar(0));
    const Scalar aq = abs(qd);
    const Scalar f3 = theta[2] > Scalar(1e-3) ? theta[2] : Scalar(1e-3);
    const Scalar f5 = theta[4] > Scalar(1e-3) ? theta[4] : Scalar(1e-3);
    const Scalar e3 = exp(-aq / f3);
    // exp(-1 / (f5 |qd|)) -> 0 as qd -> 0 (and its derivatives too).
    const Scalar e5 = aq > Scalar(0) ? exp(-Scalar(1) / (f5 * aq)) : Scalar(0);
    if (jac != nullptr) {
      jac[0] = sg;
      jac[1] = -sg * e3;
      jac[2] = -theta[1] * sg * e3 * aq / (f3 * f3);
      jac[3] = -sg * e5;
      jac[4] = aq > Scalar(0) ? -theta[3] * sg * e5 / (f5 * f5 * aq) : Scalar(0);
      jac[5] = qd;
    }
    return theta[0] * sg - theta[1] * sg * e3 - theta[3] * sg * e5 + theta[5] * qd;
  }
};

/// Survey Eq. 6: tau_f = (f1 + f2 sech(f3 qd)) tanh(f4 qd) + beta qd,
/// theta = (f1 [Nm], f2 [Nm], f3 [s/rad], f4 [s/rad] > 0, beta [Nm s/rad]).
template <>
struct NonlinearFriction<NonlinearFrictionModel::eq6> {
  static constexpr int kNumParams = 5;
  static constexpr const char* kNames[kNumParams] = {"f1", "f2", "f3", "f4", "beta"};
  static constexpr bool kIsScale[kNumParams] = {false, false, true, true, false};
  template <typename Scalar>
  static void clamp_parameters(Scalar* theta) noexcept {
    if (!(theta[3] > Scalar(1e-3))) theta[3] = Scalar(1e-3);
  }
  template <typename Scalar>
  static Scalar torque(const Scalar* theta, Scalar qd, Scalar* jac) noexcept {
    using std::cosh;
    using std::tanh;
    const Scalar sech3 = Scalar(1) / cosh(theta[2] * qd);
    const Scalar t3 = tanh(theta[2] * qd);
    const Scalar t4 = tanh(theta[3] * qd);
    const Scalar a = theta[0] + theta[1] * sech3;
    if (jac != nullptr) {
      jac[0] = t4;
      jac[1] = sech3 * t4;
      jac[2] = -theta[1] * sech3 * t3 * qd * t4;
      jac[3] = a * (Scalar(1) - t4 * t4) * qd;
      jac[4] = qd;
    }
    return a * t4 + theta[4] * qd;
  }
};

}  // namespace dyncal
