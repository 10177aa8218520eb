#pragma once
// The arm of the drive images (port/cortex_m/app/drive.cpp) and of the host tests of the drive
// application: lib/'s port::Joints over a simulation of the generated robot model, so that a drive
// can play runs without hardware (the stand-in for a drive maker's encoders and
// current loop). The arm's truth: its standard parameters (the robot file's), the reflected rotor
// inertias, Eq. 7 friction per joint, forward dynamics by RK4 (M(q) + diag(Ia)) qdd = tau - h(q, qd)
// - Fc sgn(qd) - beta qd with the command held over the period, encoder quantisation, and a torque
// measurement with Gaussian noise (Box-Muller on a xorshift64* generator). The same physics as the
// host simulated drive's default scenario (host_sim/drive/drive_plant_of.hpp), written
// independently of it and of the drive application it feeds.
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
#include <cstdint>

#include "dyncal/port.hpp"

namespace dyncal::replay {

/// The arm's physics: standard parameters [kNumStandard], and per joint Coulomb [Nm] and viscous
/// [Nm s/rad] friction, reflected rotor inertia [kg m^2], torque noise std [Nm], encoder quantum
/// [rad] (0: none); the control period [s], RK4 substeps per period, the noise generator's seed.
struct SimulatedArmPhysics {
  const double* standard;
  const double *coulomb, *viscous, *rotor_inertia, *tau_noise_std, *quantum;
  double period_s;
  int substeps;
  std::uint64_t seed;
};

template <class Robot, typename Scalar>
class SimulatedArm final : public port::Joints<Scalar> {
 public:
  static constexpr int N = Robot::kNumJoints;
  using Vec = Eigen::Matrix<Scalar, N, 1>;
  using Mat = Eigen::Matrix<Scalar, N, N>;

  using Physics = SimulatedArmPhysics;

  explicit SimulatedArm(const Physics& p) noexcept
      : period_(static_cast<Scalar>(p.period_s)), substeps_(p.substeps), rng_(p.seed | 1u) {
    for (int i = 0; i < Robot::kNumStandard; ++i) phi_[i] = static_cast<Scalar>(p.standard[i]);
    for (int j = 0; j < N; ++j) {
      fc_[j] = static_cast<Scalar>(p.coulomb[j]);
      beta_[j] = static_cast<Scalar>(p.viscous[j]);
      ia_[j] = static_cast<Scalar>(p.rotor_inertia[j]);
      noise_[j] = static_cast<Scalar>(p.tau_noise_std[j]);
      quantum_[j] = static_cast<Scalar>(p.quantum[j]);
    }
  }

  /// Replaces the arm's standard parameters [kNumStandard] (a load on a link, say); between runs.
  void set_standard(const double* standard) noexcept {
    for (int i = 0; i < Robot::kNumStandard; ++i) phi_[i] = static_cast<Scalar>(standard[i]);
  }

  void place(const Scalar* q, const Scalar* qd) noexcept override {
    q_ = Eigen::Map<const Vec>(q);
    qd_ = Eigen::Map<const Vec>(qd);
  }

  void sense(Scalar* q) noexcept override {
    for (int j = 0; j < N; ++j) q[j] = quantum_[j] > 0 ? quantum_[j] * std::round(q_[j] / quantum_[j]) : q_[j];
  }

  void actuate(const Scalar* tau_command, Scalar* tau_measured) noexcept override {
    const Vec tau = Eigen::Map<const Vec>(tau_command);
    for (int j = 0; j < N; ++j) tau_measured[j] = tau[j] + noise_[j] * normal();
    const Scalar h = period_ / static_cast<Scalar>(substeps_);
    for (int s = 0; s < substeps_; ++s) {
      Vec k1q = qd_, k1v, k2q, k2v, k3q, k3v, k4q, k4v;
      acceleration(q_, qd_, tau, k1v);
      k2q = qd_ + Scalar(0.5) * h * k1v;
      acceleration(q_ + Scalar(0.5) * h * k1q, k2q, tau, k2v);
      k3q = qd_ + Scalar(0.5) * h * k2v;
      acceleration(q_ + Scalar(0.5) * h * k2q, k3q, tau, k3v);
      k4q = qd_ + h * k3v;
      acceleration(q_ + h * k3q, k4q, tau, k4v);
      q_ += h / Scalar(6) * (k1q + Scalar(2) * k2q + Scalar(2) * k3q + k4q);
      qd_ += h / Scalar(6) * (k1v + Scalar(2) * k2v + Scalar(2) * k3v + k4v);
    }
  }

 private:
  /// qdd of the arm at (q, qd) under tau: forward dynamics by a Cholesky solve.
  void acceleration(const Vec& q, const Vec& qd, const Vec& tau, Vec& qdd) const noexcept {
    Mat M;
    Robot::mass_matrix(q, phi_, M);
    M.diagonal() += ia_;
    Vec bias;
    Robot::inverse_dynamics(q, qd, Vec::Zero().eval(), phi_, bias);
    Vec rhs = tau - bias;
    for (int j = 0; j < N; ++j) {
      const Scalar sign = qd[j] > 0 ? Scalar(1) : (qd[j] < 0 ? Scalar(-1) : Scalar(0));
      rhs[j] -= fc_[j] * sign + beta_[j] * qd[j];
    }
    qdd = M.llt().solve(rhs);
  }

  /// A standard normal draw (Box-Muller; the second value of each pair kept for the next call).
  Scalar normal() noexcept {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const Scalar u1 = uniform(), u2 = uniform();
    const Scalar r = std::sqrt(Scalar(-2) * std::log(u1));
    const Scalar a = Scalar(6.283185307179586) * u2;
    spare_ = r * std::sin(a);
    has_spare_ = true;
    return r * std::cos(a);
  }
  /// Uniform on (0, 1] from xorshift64* (Vigna 2016).
  Scalar uniform() noexcept {
    rng_ ^= rng_ >> 12;
    rng_ ^= rng_ << 25;
    rng_ ^= rng_ >> 27;
    const std::uint64_t x = rng_ * 2685821657736338717ull;
    return (static_cast<Scalar>(x >> 40) + Scalar(1)) / Scalar(16777216.0);
  }

  Eigen::Matrix<Scalar, Robot::kNumStandard, 1> phi_;
  Vec fc_, beta_, ia_, noise_, quantum_;
  Vec q_ = Vec::Zero(), qd_ = Vec::Zero();
  Scalar period_;
  int substeps_;
  std::uint64_t rng_;
  Scalar spare_ = 0;
  bool has_spare_ = false;
};

}  // namespace dyncal::replay
