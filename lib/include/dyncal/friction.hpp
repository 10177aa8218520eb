#pragma once

#include <cmath>

namespace dyncal {

/// Per-joint terms of the linear identification model tau = [Y_b  K_f] phi (survey Eq. 10, 12).
/// Each term adds one column per joint, acting on that joint's torque only.
namespace term {
enum : unsigned {
  coulomb = 1u << 0,        ///< Fc * sgn(qd)                         [Nm]        (Eq. 3, 7)
  viscous = 1u << 1,        ///< beta * qd                            [Nm s/rad]  (Eq. 3, 7)
  power = 1u << 2,          ///< f1 * qd^(1/3) (signed cube root)     [Nm (s/rad)^(1/3)] (Eq. 8)
  load = 1u << 3,           ///< f1 * |tau_load| * sgn(qd)            [-]         (Eq. 9, see below)
  rotor_inertia = 1u << 4,  ///< Ia * qdd (joint-side reflected rotor inertia) [kg m^2]
  offset = 1u << 5,         ///< constant torque offset               [Nm]
};
}  // namespace term

/// The survey's linear friction models as term sets.
inline constexpr unsigned kFrictionEq7 = term::coulomb | term::viscous;
inline constexpr unsigned kFrictionEq8 = kFrictionEq7 | term::power;
inline constexpr unsigned kFrictionEq9 = kFrictionEq7 | term::load;

inline constexpr int kNumTerms = 6;

/// Term bit for position `i` in the fixed column order coulomb, viscous, power, load,
/// rotor_inertia, offset.
constexpr unsigned term_bit(int i) noexcept {
  return 1u << i;
}

/// Short name of a single term ("Fc", "Fv", "Fp", "Fl", "Ia", "offset").
constexpr const char* term_name(unsigned t) noexcept {
  switch (t) {
    case term::coulomb:
      return "Fc";
    case term::viscous:
      return "Fv";
    case term::power:
      return "Fp";
    case term::load:
      return "Fl";
    case term::rotor_inertia:
      return "Ia";
    case term::offset:
      return "offset";
    default:
      return "?";
  }
}

/// sgn(x) with sgn(0) = 0.
template <typename Scalar>
constexpr Scalar sgn(Scalar x) noexcept {
  return x > Scalar(0) ? Scalar(1) : (x < Scalar(0) ? Scalar(-1) : Scalar(0));
}

/// The regressor entry of one term for one joint: the coefficient of that term's parameter in the
/// joint's torque. qd [rad/s], qdd [rad/s^2], tau_load [Nm].
/// Eq. 9 is implemented as f1 * |tau_load| * sgn(qd): the literal f1 * tau_load is a linear
/// combination of the rigid-body columns when tau_load comes from the rigid-body model, so it
/// would not be identifiable; load-dependent friction opposes motion and grows with |load|.
template <typename Scalar>
Scalar term_column(unsigned t, Scalar qd, Scalar qdd, Scalar tau_load) noexcept {
  using std::abs;
  using std::cbrt;
  switch (t) {
    case term::coulomb:
      return sgn(qd);
    case term::viscous:
      return qd;
    case term::power:
      return cbrt(qd);
    case term::load:
      return abs(tau_load) * sgn(qd);
    case term::rotor_inertia:
      return qdd;
    case term::offset:
      return Scalar(1);
    default:
      return Scalar(0);
  }
}

}  // namespace dyncal
