// Effect terms found by the residual diagnosis (dyncal diagnose) and carried in the parameter
// table beside the linear model, so that a drive's feed-forward includes them.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>

#include "dyncal/assert.hpp"
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
  coupling = 8,             ///< motor turning with v = qd_i + r qd_j: f = c0 sgn(v) + c1 v + c2 a,
                            ///< a = qdd_i + r qdd_j; f on joint i, r f on joint j (the transmission's
                            ///< transpose), r = sign * shape (shape: the ratio |r|; 0 means 1)
  shape = 9,                ///< host only: a cubic spline of one variable (dyncal diagnose's shape beyond its
                            ///< table, fitted by identify); no table term (effect_term_valid refuses it) and
                            ///< no columns here (effect_columns returns 0)
};

/// One effect term: 20 bytes in the table (kind, joint, joint2, sign, shape, c0, c1, c2).
struct EffectTerm {
  EffectKind kind = EffectKind::offset;
  std::uint8_t joint = 0;   ///< 0-based
  std::uint8_t joint2 = 0;  ///< coupling only
  std::int8_t sign = 1;     ///< coupling only: +1 or -1
  float shape = 0;          ///< velocity scale [rad/s] (stribeck), cycles per revolution (periodic), or the
                            ///< coupling's ratio |r| (0: 1)
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
  if (e.kind == EffectKind::coupling && e.shape < 0.0f) return false;
  if (e.kind == EffectKind::coupling &&
      (e.joint2 >= num_joints || e.joint2 == e.joint || (e.sign != 1 && e.sign != -1)))
    return false;
  return true;
}

/// The regressor columns of an effect at one sample: the torque it adds is sum_k c_k column[k] on
/// its joint and, for a coupling, `sign` (the signed ratio r) times the same on its second joint (the motor's torque
/// reflected by the transmission). One joint's q [rad], qd [rad/s], qdd [rad/s^2] and tau_rb [Nm]
/// (the rigid-body torque, read by load friction); a coupling's motor turns with v = qd + sign qd2,
/// a = qdd + sign qdd2 (sign: the term's signed ratio r, sign * (shape > 0 ? shape : 1)). shape: velocity scale [rad/s]
/// (stribeck) or cycles per revolution (position_periodic). Writes the kind's columns (1 to 3) and returns their count;
/// 0 for an unknown kind. The coefficients' meaning is EffectKind's.
template <typename Scalar>
int effect_columns(EffectKind kind, Scalar shape, Scalar sign, Scalar q, Scalar qd, Scalar qdd, Scalar qd2, Scalar qdd2,
                   Scalar tau_rb, Scalar columns[3]) noexcept {
  using std::abs;
  switch (kind) {
    case EffectKind::stribeck: {
      const Scalar x = qd / shape;
      columns[0] = sgn(qd) * std::exp(-x * x);
      return 1;
    }
    case EffectKind::asymmetric_friction:
      columns[0] = qd > Scalar(0) ? Scalar(1) : Scalar(0);
      columns[1] = qd > Scalar(0) ? qd : Scalar(0);
      return 2;
    case EffectKind::velocity_power:
      columns[0] = std::cbrt(qd);
      return 1;
    case EffectKind::load_friction:
      columns[0] = abs(tau_rb) * sgn(qd);
      return 1;
    case EffectKind::rotor_inertia:
      columns[0] = qdd;
      return 1;
    case EffectKind::offset:
      columns[0] = Scalar(1);
      return 1;
    case EffectKind::position_periodic:
      columns[0] = std::sin(shape * q);
      columns[1] = std::cos(shape * q);
      return 2;
    case EffectKind::coupling: {
      const Scalar v = qd + sign * qd2, a = qdd + sign * qdd2;
      columns[0] = sgn(v);
      columns[1] = v;
      columns[2] = a;
      return 3;
    }
    case EffectKind::shape:
      return 0;
  }
  return 0;
}

/// Adds the torques [Nm] of `count` effect terms to tau (N joints): sum_k c_k effect_columns(...)[k].
/// q [rad], qd [rad/s], qdd [rad/s^2], tau_rb [Nm] the rigid-body torque (for load friction).
/// Allocation-free. Precondition: every term is effect_term_valid for N joints (a table passes
/// table_check before its terms are used).
template <typename Scalar, int N>
void add_effect_torques(const EffectTerm* effects, int count, const Eigen::Matrix<Scalar, N, 1>& q,
                        const Eigen::Matrix<Scalar, N, 1>& qd, const Eigen::Matrix<Scalar, N, 1>& qdd,
                        const Eigen::Matrix<Scalar, N, 1>& tau_rb, Eigen::Matrix<Scalar, N, 1>& tau) noexcept {
  for (int i = 0; i < count; ++i) {
    const EffectTerm& e = effects[i];
    DYNCAL_ASSERT(effect_term_valid(e, N));
    const int j = e.joint, k = e.kind == EffectKind::coupling ? e.joint2 : e.joint;
    // A coupling's signed ratio r: the second joint turns the motor by r, and takes r times its torque.
    const Scalar s = Scalar(e.sign) * (e.kind == EffectKind::coupling && e.shape > 0.0f ? Scalar(e.shape) : Scalar(1));
    Scalar columns[3];
    const int m = effect_columns(e.kind, Scalar(e.shape), s, q[j], qd[j], qdd[j], qd[k], qdd[k], tau_rb[j], columns);
    if (m == 0) continue;
    Scalar f = Scalar(e.c[0]) * columns[0];
    for (int c = 1; c < m; ++c) f += Scalar(e.c[c]) * columns[c];
    tau[j] += f;
    if (e.kind == EffectKind::coupling) tau[k] += s * f;
  }
}

}  // namespace dyncal
