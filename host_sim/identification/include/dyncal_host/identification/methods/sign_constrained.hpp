#pragma once
// Least squares with sign constraints: min ||R x - z||^2 subject to x_i >= 0 for the given indices,
// the others free (Lawson and Hanson 1974, Solving Least Squares Problems, ch. 23: NNLS, with free
// variables never entering the active set). Used where a fit must give what a drive accepts: Coulomb
// and viscous friction and rotor inertia cannot be negative (lib/ table_check.hpp), and a joint with
// negligible friction has an unconstrained estimate that is negative half the time.

#include <Eigen/Core>
#include <vector>

namespace dyncal::host {

struct SignConstrainedSolution {
  Eigen::VectorXd x;                  ///< the constrained minimiser
  std::vector<int> held;              ///< constrained indices held at 0 (the active set), ascending
  Eigen::VectorXd inverse_gram_diag;  ///< diag((R_F^T R_F)^-1) on the free set F, 0 on held indices
  double residual_increase = 0;       ///< ||R x - z||^2 - ||R x0 - z||^2 (x0: the unconstrained minimiser) >= 0
  int iterations = 0;
};

/// R: m x n (m >= n) of full column rank (e.g. the triangular factor of a weighted regressor, z its
/// rotated right-hand side); `nonnegative`: the indices with x_i >= 0; `start`: the unconstrained
/// minimiser (x0 = R \ z). When x0 satisfies the constraints it is returned unchanged (bit for bit)
/// with no index held. Otherwise the Karush-Kuhn-Tucker point: x_i = 0 and its gradient
/// component d/dx_i ||R x - z||^2 >= 0 on the held indices, the free ones at their least-squares
/// values given those. Throws InputError for indices out of range, sizes that do not match, or a
/// rank-deficient R.
SignConstrainedSolution sign_constrained_least_squares(const Eigen::MatrixXd& R, const Eigen::VectorXd& z,
                                                       const std::vector<int>& nonnegative,
                                                       const Eigen::VectorXd& start);

}  // namespace dyncal::host
