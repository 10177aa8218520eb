#pragma once
// Log-Cholesky parametrisation of one link's inertial parameters (Rucker and Wensing 2022): the
// pseudo-inertia J = L L^T (Wensing et al. 2017) with L lower triangular and diagonal exp(theta[0..3]),
// so every theta in R^10 is a physically consistent link (J positive definite) and every consistent
// link has a theta.

#include <Eigen/Core>

namespace dyncal::host {

/// L of theta (10): diagonal exp(theta[0..3]), below the diagonal theta[4..9] row by row
/// ((1,0), (2,0), (2,1), (3,0), (3,1), (3,2)).
Eigen::Matrix4d log_cholesky_factor(const double* theta);

/// theta (10) of the nearest positive definite pseudo-inertia to J (nearest_positive_definite).
void theta_from_pseudo_inertia(const Eigen::Matrix4d& J, double* theta);

/// The link's 10 standard parameters [XX XY XZ YY YZ ZZ MX MY MZ M] (Khalil-Kleinfinger, link
/// frame) of theta, and if jac is given d phi / d theta (10 x 10).
void standard_from_theta(const double* theta, double* phi10, Eigen::Matrix<double, 10, 10>* jac = nullptr);

/// Smallest eigenvalue of L L^T (the square of L's smallest singular value) [kg m^2 or kg].
double theta_min_eigenvalue(const double* theta);

}  // namespace dyncal::host
