// What both example consumers of lib/ do, on their own scalar: simulate the er20 (its generated
// inverse dynamics at the nominal standard parameters, plus Coulomb and viscous friction) along a
// Fourier excitation, identify the base parameters and friction by streaming least squares (Eq. 15)
// with lib/'s identification model, and predict the torque of a second, unseen trajectory.
// Everything is fixed-size; no heap.
#pragma once

#include <cmath>

#include "dyncal/fourier_trajectory.hpp"
#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/streaming_least_squares.hpp"

namespace example {

using Robot = dyncal::generated::er20::Robot;
using Model = dyncal::IdentificationModel<Robot, dyncal::kFrictionEq7>;
constexpr int N = Robot::kNumJoints;

template <typename Scalar>
using Vec = Eigen::Matrix<Scalar, N, 1>;

/// The arm's torque [Nm]: rigid body at the nominal parameters, Fc = 10 Nm and beta = 5 Nm s/rad
/// on every joint.
template <typename Scalar>
Vec<Scalar> measured_torque(const Vec<Scalar>& q, const Vec<Scalar>& qd, const Vec<Scalar>& qdd) {
  Eigen::Matrix<Scalar, Robot::kNumStandard, 1> phi;
  for (int i = 0; i < Robot::kNumStandard; ++i) phi[i] = Scalar(dyncal::generated::er20::kNominalStandard[i]);
  Vec<Scalar> tau;
  Robot::inverse_dynamics(q, qd, qdd, phi, tau);
  for (int j = 0; j < N; ++j) tau[j] += Scalar(10) * dyncal::sgn(qd[j]) + Scalar(5) * qd[j];
  return tau;
}

/// A 5-harmonic Fourier trajectory (Eq. 27) at f_f = 0.1 Hz, amplitudes from `seed`.
template <typename Scalar>
dyncal::FourierTrajectory<Scalar, N, 5> trajectory(unsigned seed) {
  dyncal::FourierTrajectory<Scalar, N, 5> t;
  t.f_f = Scalar(0.1);
  t.harmonics = 5;
  for (int j = 0; j < N; ++j) {
    for (int l = 0; l < 5; ++l) {
      seed = seed * 1103515245u + 12345u;  // a fixed linear congruential sequence: reproducible
      const Scalar u = Scalar((seed >> 8) % 2001) / Scalar(1000) - Scalar(1);
      t.a(j, l) = Scalar(0.3) * u / Scalar(l + 1);
      t.b(j, l) = Scalar(0.3) * u * Scalar(j % 2 ? 1 : -1) / Scalar(l + 2);
    }
  }
  return t;
}

/// Relative RMS prediction error on a second trajectory, after identifying on the first one; or a
/// negative value when an update or the solve did not return ok.
template <typename Scalar>
Scalar identify_and_validate(dyncal::StreamingLeastSquares<Scalar, Model::kNumParams>& ls, int samples) {
  typename Model::template Regressor<Scalar> K;
  const Vec<Scalar> zero = Vec<Scalar>::Zero();
  Vec<Scalar> q, qd, qdd;
  const auto fit = trajectory<Scalar>(1);
  for (int s = 0; s < samples; ++s) {
    fit.evaluate(Scalar(10) * Scalar(s) / Scalar(samples), q, qd, qdd);
    Model::regressor(q, qd, qdd, zero, K);
    if (ls.update(K, measured_torque(q, qd, qdd)) != dyncal::UpdateStatus::ok) return Scalar(-1);
  }
  typename Model::template ParamVector<Scalar> phi;
  if (ls.solve(phi) != dyncal::UpdateStatus::ok) return Scalar(-1);
  Scalar se = 0, st = 0;
  const auto check = trajectory<Scalar>(2);
  for (int s = 0; s < samples; ++s) {
    check.evaluate(Scalar(10) * Scalar(s) / Scalar(samples), q, qd, qdd);
    Model::regressor(q, qd, qdd, zero, K);
    const Vec<Scalar> tau = measured_torque(q, qd, qdd);
    se += (tau - K * phi).squaredNorm();
    st += tau.squaredNorm();
  }
  using std::sqrt;
  return sqrt(se / st);
}

}  // namespace example
