#pragma once
// Standard (10 per link) and base parameters of the er20 for the survey study: the linear map
// between them (Gautier 1990) and the CAD prior. One link's physical parametrisation (Table 5) and
// pseudo-inertia are identification's, for any robot (inertial_parameters.hpp).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "dyncal_host/model/inertial_parameters.hpp"

namespace dyncal::host {

inline constexpr int kLinks = 6;
inline constexpr int kStandard = 60;  ///< [XX XY XZ YY YZ ZZ MX MY MZ M] per link (Khalil-Kleinfinger)
inline constexpr int kBase = 36;

/// phi_b = G phi (36 x 60), the generated standard_to_base as a matrix, and its pseudo-inverse.
const Eigen::MatrixXd& base_map();
const Eigen::MatrixXd& base_map_pinv();

/// The set standard parameters (robot file / kNominalStandard).
Eigen::VectorXd set_standard();

/// Which parameters a CAD prior's relative errors are drawn on.
enum class PriorErrors {
  table5,    ///< Table 5's: mass, centre of mass, inertia about it (what a CAD tool reports)
  standard,  ///< the standard parameters (inertia about the link frame, first moments, mass)
};

/// A Gaussian CAD prior N(mean, covariance) on the standard parameters (60). The covariance is
/// block diagonal (links independent, 10 x 10 blocks); `whitening` W is block lower triangular with
/// W^T W = covariance^-1, so that the prior's residual is W (phi - mean) (dimensionless).
struct CadPrior {
  Eigen::VectorXd mean;
  Eigen::MatrixXd covariance;
  Eigen::MatrixXd whitening;
};

/// A seeded CAD prior: every nonzero set value of the parameters `on` names times (1 + u), u
/// uniform in [-relative_error, relative_error] (structural zeros stay zero), converted to standard
/// parameters. Standard deviation of each drawn parameter: relative_error x max(|value|, 5 % of
/// the largest of its kind in the link) (kinds: mass; centre of mass or first moments; inertia), so
/// that a zero value still has a finite scale; on Table 5's parameters propagated to the standard
/// ones through the map's Jacobian at the mean (linearised). Throws InputError if a link has a
/// kind with no nonzero value (no scale) or a covariance block is not positive definite (a zero mass).
CadPrior cad_prior(double relative_error, std::uint64_t seed, PriorErrors on = PriorErrors::table5);

/// The minimum-norm standard parameters with base parameters phi_b: G^+ phi_b, what a
/// pseudo-inverse of the standard regressor returns (survey Tables 5, 6).
Eigen::VectorXd minimum_norm_standard(const Eigen::VectorXd& phi_b);

/// The most probable standard parameters given the base parameters phi_b (36) and the prior
/// N(m, P): minimise (phi - m)^T P^-1 (phi - m) subject to G phi = phi_b, i.e.
/// phi = m + P G^T (G P G^T)^+ (phi_b - G m).
Eigen::VectorXd standard_from_base(const Eigen::VectorXd& phi_b, const CadPrior& prior);

}  // namespace dyncal::host
