#pragma once
// One link's inertial parameters: the 10 standard parameters [XX XY XZ YY YZ ZZ MX MY MZ M]
// (Khalil-Kleinfinger, about the link frame's origin, link frame; kg m^2, kg m, kg) and the
// physical parametrisation (mass, centre of mass, inertia about it; survey Table 5), related by the
// parallel-axis (Huygens-Steiner) theorem. Heap-free, exception-free: the identification's
// reports, the simulated drives' loads and the drive images use the same two functions.

#include <Eigen/Core>
#include <array>

namespace dyncal {

/// Table 5's parametrisation of one link from its 10 standard parameters phi10: m [kg], centre of
/// mass X Y Z [m] (link frame), inertia about the centre of mass I11 I12 I13 I22 I23 I33 [kg m^2].
/// A zero mass (a minimum-norm estimate of an unidentifiable link) has no centre of mass: taken at
/// the origin.
inline std::array<double, 10> physical_parameters(const double* p) noexcept {
  const double m = p[9];
  const Eigen::Vector3d c =
      m != 0.0 ? Eigen::Vector3d(Eigen::Vector3d(p[6], p[7], p[8]) / m) : Eigen::Vector3d(Eigen::Vector3d::Zero());
  Eigen::Matrix3d I;
  I << p[0], p[1], p[2], p[1], p[3], p[4], p[2], p[4], p[5];
  // Parallel axis: I_origin = I_com + m (c^T c 1 - c c^T).
  const Eigen::Matrix3d Ic = I - m * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
  return {m, c[0], c[1], c[2], Ic(0, 0), Ic(0, 1), Ic(0, 2), Ic(1, 1), Ic(1, 2), Ic(2, 2)};
}

/// The inverse: the 10 standard parameters phi10 of Table 5's (m, X Y Z, I about the centre of
/// mass), and if `jac` is given d phi10 / d physical (10 x 10, row-major).
inline void standard_from_physical(const std::array<double, 10>& v, double* p, double* jac = nullptr) noexcept {
  const double m = v[0];
  const Eigen::Vector3d c(v[1], v[2], v[3]);
  Eigen::Matrix3d Ic;
  Ic << v[4], v[5], v[6], v[5], v[7], v[8], v[6], v[8], v[9];
  const Eigen::Matrix3d S = c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose();
  const Eigen::Matrix3d I = Ic + m * S;
  constexpr int kRow[6] = {0, 0, 0, 1, 1, 2}, kCol[6] = {0, 1, 2, 1, 2, 2};
  for (int k = 0; k < 6; ++k) p[k] = I(kRow[k], kCol[k]);
  for (int a = 0; a < 3; ++a) p[6 + a] = m * c[a];
  p[9] = m;
  if (!jac) return;
  Eigen::Map<Eigen::Matrix<double, 10, 10, Eigen::RowMajor>> J(jac);
  J.setZero();
  for (int k = 0; k < 6; ++k) {
    J(k, 0) = S(kRow[k], kCol[k]);
    J(k, 4 + k) = 1.0;
    for (int a = 0; a < 3; ++a) {
      // d/dc_a of m (c^T c 1 - c c^T) = m (2 c_a 1 - e_a c^T - c e_a^T).
      Eigen::Matrix3d E = 2.0 * c[a] * Eigen::Matrix3d::Identity();
      E.row(a) -= c.transpose();
      E.col(a) -= c;
      J(k, 1 + a) = m * E(kRow[k], kCol[k]);
    }
  }
  for (int a = 0; a < 3; ++a) {
    J(6 + a, 0) = c[a];
    J(6 + a, 1 + a) = m;
  }
  J(9, 0) = 1.0;
}

/// Adds a rigid load to a link's standard parameters phi10 (a payload fixed to it): mass [kg],
/// centre of mass `com` [m] and inertia about it `inertia` [kg m^2: ixx ixy ixz iyy iyz izz], all in
/// the link's frame. Standard parameters add: the load's about the link origin are added.
inline void add_rigid_load(double* phi10, double mass, const double com[3], const double inertia[6]) noexcept {
  double load[10];
  standard_from_physical(
      {mass, com[0], com[1], com[2], inertia[0], inertia[1], inertia[2], inertia[3], inertia[4], inertia[5]}, load);
  for (int i = 0; i < 10; ++i) phi10[i] += load[i];
}

}  // namespace dyncal
