#pragma once
// Random physically consistent link parameters for tests.

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <random>

namespace dyncal::test {

/// One rigid body: mass [kg], centre of mass c [m] (link frame), inertia about c [kg m^2].
struct Body {
  double m;
  Eigen::Vector3d c;
  Eigen::Matrix3d Ic;
};

/// K draws of `dist` as a vector, sequenced: the last entry drawn first. Written out, as a
/// constructor's arguments `v(d(rng), d(rng), d(rng))` are evaluated in an order C++ leaves
/// unspecified (GCC: last first; clang: first first), and the same seed then gave a compiler its own
/// data. Last first keeps the data these tests were written against (GCC's).
template <int K, class Engine, class Dist>
Eigen::Matrix<double, K, 1> draws_last_first(Engine& rng, Dist& dist) {
  Eigen::Matrix<double, K, 1> v;
  for (int i = K - 1; i >= 0; --i) v[i] = dist(rng);
  return v;
}

/// Unit quaternion (w, x, y, z) = normalised uniform(-0.5, 0.5) draws: a random rotation.
inline Eigen::Matrix3d random_rotation(std::mt19937& rng, std::uniform_real_distribution<double>& u) {
  const Eigen::Vector4d a = draws_last_first<4>(rng, u).array() - 0.5;
  return Eigen::Quaterniond(a[0], a[1], a[2], a[3]).normalized().toRotationMatrix();
}

/// A random physically consistent body: principal moments satisfying the triangle inequality,
/// random principal axes.
inline Body random_body(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Body b;
  b.m = 0.5 + 9.5 * u(rng);
  b.c = (draws_last_first<3>(rng, u).array() - 0.5).matrix() * 0.4;
  // Second moments of a mass distribution: J = diag(j) >= 0, I = tr(J) - J.
  const Eigen::Vector3d j = (0.01 + 0.2 * draws_last_first<3>(rng, u).array()).matrix();
  const Eigen::Matrix3d principal = (Eigen::Vector3d::Constant(j.sum()) - j).asDiagonal();
  const Eigen::Matrix3d R = random_rotation(rng, u);
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
