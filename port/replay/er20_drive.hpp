#pragma once
// The er20 drive of the Cortex-M drive images (port/cortex_m/app/drive.cpp, drive_period.cpp) and of
// the host tests that run the same drive application (tests/support/er20_drive.hpp): the models it
// runs, its settings (er20_ratings.hpp: the robot file's ratings, the host simulated drive's
// default scenario of the loop and the motors), its simulated arm's physics, and the tables — the
// factory table (nominal base parameters, no friction) and the arm's true table (its base
// parameters with the rotor inertias absorbed where the model absorbs them, its Eq. 7 friction and
// rotor inertias, no offset: what a perfect calibration flashes) — and a run inside its ranges.
#include <Eigen/Core>
#include <cstdint>

#include "dyncal/drive/drive_application.hpp"
#include "dyncal/drive/term_sets.hpp"
#include "dyncal/generated/er20/robot.hpp"
#include "er20_joint_ratings.hpp"
#include "er20_ratings.hpp"
#include "simulated_arm.hpp"

namespace dyncal::replay {

using Er20 = dyncal::generated::er20::Robot;
/// dyncal calibrate's default model: Eq. 7 friction, the rotor inertias, offsets.
inline constexpr unsigned kFullTerms = kFrictionEq7 | term::rotor_inertia | term::offset;
/// The models the drive runs: Eq. 7 (the factory table's) and the full model.
using DriveModels = drive::TermSets<Er20, kFrictionEq7, kFullTerms>;
using FullModel = IdentificationModel<Er20, kFullTerms>;

template <typename Scalar, std::size_t RingSamples>
using Er20Drive = drive::DriveApplication<DriveModels, Scalar, RingSamples>;

/// The drive's settings: the loop of the host simulated drive's default scenario, the robot file's
/// ratings, the encoders' quantum, the motors' reflected rotor inertias and the torque sensors'
/// noise (robots/er20/drive.json).
template <class Application>
typename Application::Settings drive_settings() {
  typename Application::Settings s;
  s.control_rate_hz = data::kControlRateHz;
  s.bandwidth_hz = data::kBandwidthHz;
  s.damping = data::kDamping;
  s.ratings = ratings();
  for (int j = 0; j < 6; ++j) {
    s.q_resolution[j] = static_cast<float>(data::kQuantum[j]);
    s.rotor_inertia[j] = data::kRotorInertia[j];
    s.tau_noise_std[j] = data::kTauNoiseStd[j];
  }
  s.nominal_standard = generated::er20::kNominalStandard;
  return s;
}

/// The simulated arm's physics (the host simulated drive's default scenario of the er20).
inline SimulatedArmPhysics arm_physics(std::uint64_t seed) {
  return {generated::er20::kNominalStandard,
          data::kCoulomb,
          data::kViscous,
          data::kRotorInertia,
          data::kTauNoiseStd,
          data::kQuantum,
          1.0 / data::kControlRateHz,
          data::kSubsteps,
          seed};
}

/// The nominal base parameters (Gautier's base map of the robot file's standard parameters).
inline Eigen::Matrix<double, Er20::kNumBase, 1> nominal_base() {
  Eigen::Matrix<double, Er20::kNumStandard, 1> standard;
  for (int i = 0; i < Er20::kNumStandard; ++i) standard[i] = generated::er20::kNominalStandard[i];
  Eigen::Matrix<double, Er20::kNumBase, 1> base;
  Er20::standard_to_base(standard, base);
  return base;
}

/// The factory table: nominal base parameters, Eq. 7 model, no friction.
inline ParameterTable factory_table() {
  using Model = IdentificationModel<Er20, kFrictionEq7>;
  Eigen::Matrix<double, Model::kNumParams, 1> phi = Eigen::Matrix<double, Model::kNumParams, 1>::Zero();
  phi.head<Er20::kNumBase>() = nominal_base();
  ParameterTable t;
  make_table<Model>(phi, t);
  return t;
}

/// The arm's own model as a table of the full model.
inline ParameterTable true_table() {
  Eigen::Matrix<double, FullModel::kNumParams, 1> phi = Eigen::Matrix<double, FullModel::kNumParams, 1>::Zero();
  phi.head<Er20::kNumBase>() = nominal_base();
  for (int j = 0; j < 6; ++j) {
    const int ia = FullModel::column(term::rotor_inertia, j), absorbed = Er20::rotor_inertia_absorbed_into(j);
    if (ia >= 0) {
      phi[ia] = data::kRotorInertia[j];
    } else if (absorbed >= 0) {
      phi[absorbed] += generated::er20::kRotorInertiaAbsorbedCoefficient[j] * data::kRotorInertia[j];
    }
    phi[FullModel::column(term::coulomb, j)] = data::kCoulomb[j];
    phi[FullModel::column(term::viscous, j)] = data::kViscous[j];
  }
  ParameterTable t;
  make_table<FullModel>(phi, t);
  return t;
}

/// The run settings of a Fourier excitation inside the er20's ranges: f_f [Hz], `periods`, sampled
/// at `fs` [Hz]; joint j's harmonics scaled by `amplitude` [rad/s].
inline drive::RunSettings excitation_run(double f_f, int periods, double fs, double amplitude) {
  drive::RunSettings r;
  r.sample_rate_hz = fs;
  r.periods = periods;
  r.trajectory.f_f = f_f;
  r.trajectory.harmonics = 3;
  const double q0[6] = {0.0, 0.5, 0.8, 0.0, 0.0, 0.0};
  for (int j = 0; j < 6; ++j) {
    r.trajectory.q0[j] = q0[j];
    for (int l = 0; l < 3; ++l) {
      r.trajectory.a(j, l) = amplitude / (l + 1) * (j % 2 == 0 ? 1.0 : -1.0);
      r.trajectory.b(j, l) = 0.5 * amplitude / (l + 1);
    }
  }
  return r;
}

}  // namespace dyncal::replay
