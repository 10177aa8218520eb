#pragma once
// One link's inertial parameters, for any robot: the 10 standard parameters [XX XY XZ YY YZ ZZ MX
// MY MZ M] (Khalil-Kleinfinger, link frame; kg m^2, kg m, kg), the physical parametrisation (mass,
// centre of mass, inertia about it; survey Table 5, lib/'s), and the pseudo-inertia that decides physical
// consistency (Wensing et al. 2017).

#include <Eigen/Core>
#include <array>

#include "dyncal/inertial_parameters.hpp"

namespace dyncal::host {

/// Table 5's parametrisation and its inverse (lib/: dyncal/inertial_parameters.hpp).
using dyncal::physical_parameters;
using dyncal::standard_from_physical;

/// Pseudo-inertia J = [Sigma h; h^T m] (4 x 4) of one link (Wensing et al. 2017): Sigma the second
/// moment about the link frame origin; physically consistent iff J is positive definite.
Eigen::Matrix4d pseudo_inertia(const double* phi10);
/// The nearest positive definite matrix to a pseudo-inertia J (Frobenius norm): eigenvalues floored
/// at 1e-4 of the largest one (and 1e-13), eigenvectors kept.
Eigen::Matrix4d nearest_positive_definite(const Eigen::Matrix4d& J);
/// Every link of phi (10 L, any number of links L) replaced by its nearest physically consistent parameters (links
/// already consistent with the floor above are kept as they are).
Eigen::VectorXd nearest_consistent(const Eigen::VectorXd& phi);
/// The 10 standard parameters of a pseudo-inertia (inverse of pseudo_inertia).
void standard_from_pseudo_inertia(const Eigen::Matrix4d& J, double* phi10);

/// d lambda_min(J_l) / d phi_l (10) at link l's standard parameters (the eigenvector's quadratic
/// form on the pseudo-inertia's linear map); lambda returned.
double pseudo_inertia_min_eigenvalue(const double* phi10, double* gradient10);

}  // namespace dyncal::host
