#pragma once
// Random physically consistent link parameters for tests.

#include <Eigen/Dense>
#include <random>

namespace dyncal::test {

/// One rigid body: mass [kg], centre of mass c [m] (link frame), inertia about c [kg m^2].
struct Body {
  double m;
  Eigen::Vector3d c;
  Eigen::Matrix3d Ic;
};

/// A random physically consistent body: principal moments satisfying the triangle inequality,
/// random principal axes.
inline Body random_body(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Body b;
  b.m = 0.5 + 9.5 * u(rng);
  b.c = Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5) * 0.4;
  // Second moments of a mass distribution: J = diag(j) >= 0, I = tr(J) - J.
  const Eigen::Vector3d j(0.01 + 0.2 * u(rng), 0.01 + 0.2 * u(rng), 0.01 + 0.2 * u(rng));
  const Eigen::Matrix3d principal = (Eigen::Vector3d::Constant(j.sum()) - j).asDiagonal();
  const Eigen::Matrix3d R =
      Eigen::Quaterniond(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized().toRotationMatrix();
  b.Ic = R * principal * R.transpose();
  return b;
}

/// Standard parameters [XX XY XZ YY YZ ZZ MX MY MZ M] about the link origin (Khalil-Kleinfinger).
inline Eigen::Matrix<double, 10, 1> standard_parameters(const Body& b) {
  const Eigen::Matrix3d Io = b.Ic + b.m * (b.c.squaredNorm() * Eigen::Matrix3d::Identity() - b.c * b.c.transpose());
  Eigen::Matrix<double, 10, 1> p;
  p << Io(0, 0), Io(0, 1), Io(0, 2), Io(1, 1), Io(1, 2), Io(2, 2), b.m * b.c.x(), b.m * b.c.y(), b.m * b.c.z(), b.m;
  return p;
}

}  // namespace dyncal::test
