#include "dyncal_host/identification/methods/inertial_parameters.hpp"

#include <Eigen/Dense>
#include <algorithm>

namespace dyncal::host {

std::array<double, 10> physical_parameters(const double* p) {
  const double m = p[9];
  // A zero mass (a minimum-norm estimate of an unidentifiable link) has no centre of mass: taken
  // at the origin, so that its errors count as 100 % instead of undefined.
  const Eigen::Vector3d c =
      m != 0.0 ? Eigen::Vector3d(Eigen::Vector3d(p[6], p[7], p[8]) / m) : Eigen::Vector3d(Eigen::Vector3d::Zero());
  Eigen::Matrix3d I;
  I << p[0], p[1], p[2], p[1], p[3], p[4], p[2], p[4], p[5];
  // Parallel axis (Huygens-Steiner): I_origin = I_com + m (c^T c 1 - c c^T).
  const Eigen::Matrix3d Ic = I - m * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
  return {m, c[0], c[1], c[2], Ic(0, 0), Ic(0, 1), Ic(0, 2), Ic(1, 1), Ic(1, 2), Ic(2, 2)};
}

void standard_from_physical(const std::array<double, 10>& v, double* p, double* jac) {
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

Eigen::Matrix4d pseudo_inertia(const double* p) {
  Eigen::Matrix3d I;
  I << p[0], p[1], p[2], p[1], p[3], p[4], p[2], p[4], p[5];
  Eigen::Matrix4d J;
  J.topLeftCorner<3, 3>() = 0.5 * I.trace() * Eigen::Matrix3d::Identity() - I;
  J.topRightCorner<3, 1>() = Eigen::Vector3d(p[6], p[7], p[8]);
  J.bottomLeftCorner<1, 3>() = Eigen::RowVector3d(p[6], p[7], p[8]);
  J(3, 3) = p[9];
  return J;
}

Eigen::Matrix4d nearest_positive_definite(const Eigen::Matrix4d& J) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(J);
  const Eigen::Vector4d ev = es.eigenvalues();
  const double floor = 1e-4 * std::max(ev.maxCoeff(), 1e-9);
  if (ev.minCoeff() >= floor) return J;
  return es.eigenvectors() * ev.cwiseMax(floor).asDiagonal() * es.eigenvectors().transpose();
}

Eigen::VectorXd nearest_consistent(const Eigen::VectorXd& phi) {
  Eigen::VectorXd out = phi;
  for (Eigen::Index l = 0; l < phi.size() / 10; ++l) {
    standard_from_pseudo_inertia(nearest_positive_definite(pseudo_inertia(phi.data() + 10 * l)), out.data() + 10 * l);
  }
  return out;
}

void standard_from_pseudo_inertia(const Eigen::Matrix4d& J, double* p) {
  const Eigen::Matrix3d S = J.topLeftCorner<3, 3>();
  const Eigen::Matrix3d I = S.trace() * Eigen::Matrix3d::Identity() - S;
  p[0] = I(0, 0);
  p[1] = I(0, 1);
  p[2] = I(0, 2);
  p[3] = I(1, 1);
  p[4] = I(1, 2);
  p[5] = I(2, 2);
  p[6] = J(0, 3);
  p[7] = J(1, 3);
  p[8] = J(2, 3);
  p[9] = J(3, 3);
}

double pseudo_inertia_min_eigenvalue(const double* phi10, double* gradient10) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(pseudo_inertia(phi10));
  if (gradient10) {
    const Eigen::Vector4d v = es.eigenvectors().col(0);
    for (int k = 0; k < 10; ++k) {
      double e[10] = {};
      e[k] = 1.0;
      gradient10[k] = v.dot(pseudo_inertia(e) * v);  // J is linear in phi
    }
  }
  return es.eigenvalues()[0];
}

}  // namespace dyncal::host
