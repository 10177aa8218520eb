#pragma once
// Standard (10 per link) and base parameters of the er20 for the survey study: the linear map
// between them (Gautier 1990), the CAD prior, and the physical parametrisation of Table 5.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace dyncal::host::survey {

inline constexpr int kLinks = 6;
inline constexpr int kStandard = 60;  ///< [XX XY XZ YY YZ ZZ MX MY MZ M] per link (Khalil-Kleinfinger)
inline constexpr int kBase = 36;

/// phi_b = G phi (36 x 60), the generated standard_to_base as a matrix, and its pseudo-inverse.
const Eigen::MatrixXd& base_map();
const Eigen::MatrixXd& base_map_pinv();

/// The set standard parameters (robot file / kNominalStandard).
Eigen::VectorXd set_standard();

/// A CAD prior: every nonzero set standard parameter times (1 + u), u uniform in
/// [-relative_error, relative_error], seeded; structural zeros stay zero.
Eigen::VectorXd cad_prior(double relative_error, std::uint64_t seed);

/// The minimum-norm standard parameters with base parameters phi_b: G^+ phi_b, what a
/// pseudo-inverse of the standard regressor returns (survey Tables 5, 6).
Eigen::VectorXd minimum_norm_standard(const Eigen::VectorXd& phi_b);

/// The most probable standard parameters given the base parameters phi_b and a prior
/// N(prior, diag(s^2)), s_i = relative_std |prior_i|: minimise sum ((phi_i - prior_i) / s_i)^2
/// subject to G phi = phi_b, i.e. phi = prior + S^2 G^T (G S^2 G^T)^+ (phi_b - G prior).
/// Parameters with a zero prior stay zero.
Eigen::VectorXd standard_from_base(const Eigen::VectorXd& phi_b, const Eigen::VectorXd& prior, double relative_std);

/// Table 5's parametrisation of one link from its 10 standard parameters: m [kg], centre of mass
/// X Y Z [m] (link frame), inertia about the centre of mass I11 I12 I13 I22 I23 I33 [kg m^2].
std::array<double, 10> physical_parameters(const double* phi10);

/// Pseudo-inertia J = [Sigma h; h^T m] (4 x 4) of one link (Wensing et al. 2017): Sigma the second
/// moment about the link frame origin; physically consistent iff J is positive definite.
Eigen::Matrix4d pseudo_inertia(const double* phi10);
/// The nearest positive definite matrix to a pseudo-inertia J (Frobenius norm): eigenvalues floored
/// at 1e-4 of the largest one (and 1e-13), eigenvectors kept.
Eigen::Matrix4d nearest_positive_definite(const Eigen::Matrix4d& J);
/// Every link of phi (60) replaced by its nearest physically consistent parameters (links already
/// consistent with the floor above are kept as they are).
Eigen::VectorXd nearest_consistent(const Eigen::VectorXd& phi);
/// The 10 standard parameters of a pseudo-inertia (inverse of pseudo_inertia).
void standard_from_pseudo_inertia(const Eigen::Matrix4d& J, double* phi10);

}  // namespace dyncal::host::survey
