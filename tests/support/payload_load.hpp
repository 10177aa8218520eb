#pragma once
// A payload on the last link for the tests: a random physically consistent load and the torque it
// adds (the generated inverse dynamics of its standard parameters alone, the simulator's truth).
#include <Eigen/Geometry>
#include <random>

#include "dyncal_host/model/compiled_robot.hpp"
#include "support/random_physical.hpp"
#include "support/simulated_log.hpp"

namespace dyncal::test {

/// The arm's total mass from robot.json's inertials [kg].
inline double arm_mass(const host::CompiledRobot& c) {
  double m = 0;
  for (int l = 0; l < c.num_joints; ++l) m += c.nominal_standard[static_cast<size_t>(10 * l + 9)];
  return m;
}

/// A load of `mass` [kg], its centre of mass uniform in a 0.2 m cube around the last
/// link's origin, a box-like inertia (principal moments of a body 2-12 cm across, random axes).
inline Body random_load(std::mt19937& rng, double mass) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Body b;
  b.m = mass;
  b.c = (draws_last_first<3>(rng, u).array() - 0.5).matrix() * 0.2;
  // Second moments about the centre of mass of a box of half sides h: m h^2 / 3 each.
  const Eigen::Vector3d h = (0.01 + 0.05 * draws_last_first<3>(rng, u).array()).matrix();
  const Eigen::Vector3d j = mass * h.cwiseAbs2() / 3.0;
  const Eigen::Matrix3d principal = (Eigen::Vector3d::Constant(j.sum()) - j).asDiagonal();
  const Eigen::Matrix3d R = random_rotation(rng, u);
  b.Ic = R * principal * R.transpose();
  return b;
}

/// The load's torque: inverse dynamics of its standard parameters on the last link alone.
inline ExtraTorque load_torque(const host::CompiledRobot& c, const Eigen::Matrix<double, 10, 1>& load) {
  Eigen::VectorXd phi = Eigen::VectorXd::Zero(c.num_standard);
  phi.tail(10) = load;
  return [&c, phi](const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd,
                   Eigen::VectorXd& tau) { tau += c.inverse_dynamics(q, qd, qdd, phi); };
}

}  // namespace dyncal::test
