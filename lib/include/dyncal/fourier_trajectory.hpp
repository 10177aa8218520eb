// Excitation trajectory as a finite Fourier series per joint (survey Eq. 27).
#pragma once

#include <Eigen/Core>

#include "dyncal/assert.hpp"
#include "dyncal/sin_cos.hpp"

namespace dyncal {

/// q_i(t) = q0_i + sum_{l=1..L} a_il / (w l) sin(w l t) - b_il / (w l) cos(w l t), w = 2 pi f_f
/// (survey Eq. 27 plus the offset q0 that centres the motion in the joint range), with its exact
/// first and second derivatives. N joints, at most H harmonics. Units: q [rad], a and b [rad/s],
/// f_f [Hz], t [s]. Allocation-free.
template <typename Scalar, int N, int H>
struct FourierTrajectory {
  Scalar f_f = Scalar(0.1);  ///< fundamental frequency [Hz]
  int harmonics = 5;         ///< L (<= H)
  Eigen::Matrix<Scalar, N, 1> q0 = Eigen::Matrix<Scalar, N, 1>::Zero();
  Eigen::Matrix<Scalar, N, H> a = Eigen::Matrix<Scalar, N, H>::Zero();
  Eigen::Matrix<Scalar, N, H> b = Eigen::Matrix<Scalar, N, H>::Zero();

  Scalar period() const noexcept { return Scalar(1) / f_f; }

  /// Position, velocity and acceleration of the first M joints (M <= N; a robot with fewer joints
  /// than a register-map-sized trajectory plays its first slots) at time t.
  /// Precondition: 0 <= harmonics <= H.
  template <int M>
  void evaluate(Scalar t, Eigen::Matrix<Scalar, M, 1>& q, Eigen::Matrix<Scalar, M, 1>& qd,
                Eigen::Matrix<Scalar, M, 1>& qdd) const noexcept {
    static_assert(M >= 1 && M <= N, "a trajectory of N joints evaluates at most N");
    DYNCAL_ASSERT(harmonics >= 0 && harmonics <= H);
    const Scalar w = Scalar(6.283185307179586476925) * f_f;
    // Reduce w t to one period first so that sin_cos stays accurate for long runs.
    const Scalar phase = w * (t - period() * std::floor(t / period()));
    q = q0.template head<M>();
    qd.setZero();
    qdd.setZero();
    for (int l = 1; l <= harmonics; ++l) {
      const Scalar wl = w * Scalar(l);
      const SinCos<Scalar> sc = sin_cos(phase * Scalar(l));
      for (int i = 0; i < M; ++i) {
        const Scalar ai = a(i, l - 1), bi = b(i, l - 1);
        q[i] += (ai * sc.sin - bi * sc.cos) / wl;
        qd[i] += ai * sc.cos + bi * sc.sin;
        qdd[i] += wl * (bi * sc.cos - ai * sc.sin);
      }
    }
  }
};

}  // namespace dyncal
