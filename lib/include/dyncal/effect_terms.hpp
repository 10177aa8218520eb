// Effect terms found by the residual diagnosis (dyncal diagnose) and carried in the parameter
// table beside the linear model, so that a drive's feed-forward includes them.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>

#include "dyncal/friction.hpp"

namespace dyncal {

enum class EffectKind : std::uint8_t {
  stribeck = 1,             ///< c0 sgn(qd) exp(-(qd / shape)^2)            (Eq. 4 minus Eq. 7; c0 = Fs - Fc)
  asymmetric_friction = 2,  ///< c0 [qd > 0] + c1 qd [qd > 0]
  velocity_power = 3,       ///< c0 qd^(1/3)                                 (Eq. 8)
  load_friction = 4,        ///< c0 |tau_rb| sgn(qd), tau_rb the rigid-body torque of the joint (Eq. 9)
  rotor_inertia = 5,        ///< c0 qdd
  offset = 6,               ///< c0
  position_periodic = 7,    ///< c0 sin(shape q) + c1 cos(shape q), shape = cycles per revolution
  coupling = 8,             ///< motor turning with v = qd_i + sign qd_j: f = c0 sgn(v) + c1 v + c2 a,
                            ///< a = qdd_i + sign qdd_j; f on joint i, sign f on joint j
};

/// One effect term: 20 bytes in the table (kind, joint, joint2, sign, shape, c0, c1, c2).
struct EffectTerm {
  EffectKind kind = EffectKind::offset;
  std::uint8_t joint = 0;   ///< 0-based
  std::uint8_t joint2 = 0;  ///< coupling only
  std::int8_t sign = 1;     ///< coupling only: +1 or -1
  float shape = 0;          ///< velocity scale [rad/s] (stribeck) or cycles per revolution (periodic)
  float c[3] = {0, 0, 0};
};

inline constexpr int kEffectTermBytes = 20;

/// Whether a term is well formed for an N-joint arm: known kind, joints in range, sign +-1,
/// finite coefficients, positive shape where the kind needs one.
inline bool effect_term_valid(const EffectTerm& e, int num_joints) noexcept {
  const auto k = static_cast<std::uint8_t>(e.kind);
  if (k < 1 || k > 8 || e.joint >= num_joints) return false;
  for (float v : e.c)
    if (!std::isfinite(v)) return false;
  if (!std::isfinite(e.shape)) return false;
  if ((e.kind == EffectKind::stribeck || e.kind == EffectKind::position_periodic) && !(e.shape > 0.0f)) return false;
  if (e.kind == EffectKind::coupling &&
      (e.joint2 >= num_joints || e.joint2 == e.joint || (e.sign != 1 && e.sign != -1)))
    return false;
  return true;
}

/// Adds the torques [Nm] of `count` effect terms to tau (N joints). q [rad], qd [rad/s],
/// qdd [rad/s^2], tau_rb [Nm] the rigid-body torque (for load friction). Allocation-free.
template <typename Scalar, int N>
void add_effect_torques(const EffectTerm* effects, int count, const Eigen::Matrix<Scalar, N, 1>& q,
                        const Eigen::Matrix<Scalar, N, 1>& qd, const Eigen::Matrix<Scalar, N, 1>& qdd,
                        const Eigen::Matrix<Scalar, N, 1>& tau_rb, Eigen::Matrix<Scalar, N, 1>& tau) noexcept {
  using std::abs;
  for (int i = 0; i < count; ++i) {
    const EffectTerm& e = effects[i];
    const int j = e.joint;
    const Scalar c0 = Scalar(e.c[0]), c1 = Scalar(e.c[1]), c2 = Scalar(e.c[2]);
    switch (e.kind) {
      case EffectKind::stribeck: {
        const Scalar x = qd[j] / Scalar(e.shape);
        tau[j] += c0 * sgn(qd[j]) * std::exp(-x * x);
        break;
      }
      case EffectKind::asymmetric_friction:
        if (qd[j] > Scalar(0)) tau[j] += c0 + c1 * qd[j];
        break;
      case EffectKind::velocity_power:
        tau[j] += c0 * std::cbrt(qd[j]);
        break;
      case EffectKind::load_friction:
        tau[j] += c0 * abs(tau_rb[j]) * sgn(qd[j]);
        break;
      case EffectKind::rotor_inertia:
        tau[j] += c0 * qdd[j];
        break;
      case EffectKind::offset:
        tau[j] += c0;
        break;
      case EffectKind::position_periodic:
        tau[j] += c0 * std::sin(Scalar(e.shape) * q[j]) + c1 * std::cos(Scalar(e.shape) * q[j]);
        break;
      case EffectKind::coupling: {
        const int k = e.joint2;
        const Scalar s = Scalar(e.sign);
        const Scalar v = qd[j] + s * qd[k], a = qdd[j] + s * qdd[k];
        const Scalar f = c0 * sgn(v) + c1 * v + c2 * a;
        tau[j] += f;
        tau[k] += s * f;
        break;
      }
    }
  }
}

}  // namespace dyncal
