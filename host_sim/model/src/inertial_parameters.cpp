#include "dyncal_host/model/inertial_parameters.hpp"

#include <Eigen/Dense>
#include <algorithm>

namespace dyncal::host {

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
