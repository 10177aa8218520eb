#include "dyncal_host/identification/methods/log_cholesky.hpp"

#include <Eigen/Dense>
#include <cmath>

#include "dyncal_host/model/inertial_parameters.hpp"

namespace dyncal::host {
namespace {

constexpr int kOffRow[6] = {1, 2, 2, 3, 3, 3};
constexpr int kOffCol[6] = {0, 0, 1, 0, 1, 2};

}  // namespace

Eigen::Matrix4d log_cholesky_factor(const double* th) {
  Eigen::Matrix4d L = Eigen::Matrix4d::Zero();
  for (int i = 0; i < 4; ++i) L(i, i) = std::exp(th[i]);
  for (int k = 0; k < 6; ++k) L(kOffRow[k], kOffCol[k]) = th[4 + k];
  return L;
}

void theta_from_pseudo_inertia(const Eigen::Matrix4d& J, double* th) {
  const Eigen::Matrix4d L = nearest_positive_definite(J).llt().matrixL();
  for (int i = 0; i < 4; ++i) th[i] = std::log(L(i, i));
  for (int k = 0; k < 6; ++k) th[4 + k] = L(kOffRow[k], kOffCol[k]);
}

void standard_from_theta(const double* th, double* phi10, Eigen::Matrix<double, 10, 10>* jac) {
  const Eigen::Matrix4d L = log_cholesky_factor(th);
  standard_from_pseudo_inertia(L * L.transpose(), phi10);
  if (!jac) return;
  for (int k = 0; k < 10; ++k) {
    Eigen::Matrix4d E = Eigen::Matrix4d::Zero();
    if (k < 4) {
      E(k, k) = L(k, k);
    } else {
      E(kOffRow[k - 4], kOffCol[k - 4]) = 1.0;
    }
    const Eigen::Matrix4d dJ = E * L.transpose() + L * E.transpose();
    double col[10];
    standard_from_pseudo_inertia(dJ, col);
    for (int i = 0; i < 10; ++i) (*jac)(i, k) = col[i];
  }
}

double theta_min_eigenvalue(const double* th) {
  // The singular values of L (not the eigenvalues of L L^T): accurate down to the smallest one.
  const Eigen::Matrix4d L = log_cholesky_factor(th);
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(L);
  const Eigen::Vector4d s = svd.singularValues();
  return s.minCoeff() * s.minCoeff();
}

}  // namespace dyncal::host
