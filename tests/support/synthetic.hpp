#pragma once
// Synthetic identification data from the generated er20 model: an excitation of sums of sines
// (a Fourier series, survey Eq. 27) and exact torques tau = K phi.

#include <Eigen/Core>
#include <cmath>

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"

namespace dyncal::test {

using Er20 = dyncal::generated::er20::Robot;

/// Joint state at time t [s] of a fixed 5-harmonic Fourier trajectory (omega_f = 0.1 Hz).
inline void fourier_state(double t, Eigen::Matrix<double, 6, 1>& q, Eigen::Matrix<double, 6, 1>& qd,
                          Eigen::Matrix<double, 6, 1>& qdd) {
  const double wf = 2.0 * M_PI * 0.1;
  for (int i = 0; i < 6; ++i) {
    q[i] = qd[i] = qdd[i] = 0.0;
    for (int l = 1; l <= 5; ++l) {
      const double a = 0.3 * std::sin(1.7 * i + 0.9 * l), b = 0.3 * std::cos(2.3 * i + 1.3 * l);
      const double w = wf * l;
      q[i] += a / w * std::sin(w * t) - b / w * std::cos(w * t);
      qd[i] += a * std::cos(w * t) + b * std::sin(w * t);
      qdd[i] += -a * w * std::sin(w * t) + b * w * std::cos(w * t);
    }
  }
}

/// Ground-truth parameters of the er20 identification model with term set Terms: nominal base
/// parameters from the description and friction Fc = 10 + 5 j, beta = 5 + 2 j (j 1-based).
template <unsigned Terms>
Eigen::Matrix<double, IdentificationModel<Er20, Terms>::kNumParams, 1> er20_truth() {
  using Model = IdentificationModel<Er20, Terms>;
  Eigen::Matrix<double, Er20::kNumStandard, 1> phi_std;
  for (int i = 0; i < Er20::kNumStandard; ++i) phi_std[i] = dyncal::generated::er20::kNominalStandard[i];
  Eigen::Matrix<double, Er20::kNumBase, 1> phi_b;
  Er20::standard_to_base(phi_std, phi_b);
  Eigen::Matrix<double, Model::kNumParams, 1> phi = Eigen::Matrix<double, Model::kNumParams, 1>::Zero();
  phi.template head<Er20::kNumBase>() = phi_b;
  for (int j = 0; j < 6; ++j) {
    if (Model::column(term::coulomb, j) >= 0) phi[Model::column(term::coulomb, j)] = 10.0 + 5.0 * (j + 1);
    if (Model::column(term::viscous, j) >= 0) phi[Model::column(term::viscous, j)] = 5.0 + 2.0 * (j + 1);
    if (Model::column(term::power, j) >= 0) phi[Model::column(term::power, j)] = 2.0 + j;
    if (Model::column(term::offset, j) >= 0) phi[Model::column(term::offset, j)] = 0.5 * (j + 1);
    if (Model::column(term::rotor_inertia, j) >= 0) phi[Model::column(term::rotor_inertia, j)] = 0.1 * (j + 1);
  }
  return phi;
}

}  // namespace dyncal::test
