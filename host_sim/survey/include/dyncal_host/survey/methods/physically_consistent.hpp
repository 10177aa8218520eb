#pragma once
// Physically consistent least squares: every link's pseudo-inertia J = L L^T (Wensing et al. 2017)
// positive definite by construction, L lower triangular with log-diagonal (log-Cholesky, Rucker and
// Wensing 2022); maximum a posteriori with the measured torques (noise sigma per joint) and a CAD
// prior on the standard parameters that pulls the directions the data cannot see. The linear
// models (and the first stage of the nonlinear ones) are identification's consistent_least_squares,
// as identify --method pcls runs it; the nonlinear friction models' second stage (which identify
// does not offer) is a structured Levenberg-Marquardt here.

#include "dyncal_host/survey/methods/methods.hpp"

namespace dyncal::host {

struct ConsistentSettings {
  int max_evaluations = 100;          ///< per stage (linear: cost evaluations; nonlinear: iterations)
  double relative_tolerance = 1e-10;  ///< on the cost and on x (MINPACK ftol, xtol)
};

/// Any of the six friction models (`model`: Eq. 7, 8, 9 in one linear stage; Eq. 4, 5, 6 after an
/// Eq. 7 stage, from friction_start); the standard parameters start from the CAD prior projected
/// onto the consistent set. Estimate::standard and ::standard_prior are the consistent parameters.
/// Throws InputError if the solver fails.
Estimate physically_consistent_ls(const RunData& data, FrictionModel model, const MethodSettings& settings,
                                  const ConsistentSettings& options = {});

/// Smallest eigenvalue of each link's pseudo-inertia (consistent iff all > 0).
std::array<double, 6> pseudo_inertia_min_eigenvalues(const Eigen::VectorXd& phi_standard);

}  // namespace dyncal::host
