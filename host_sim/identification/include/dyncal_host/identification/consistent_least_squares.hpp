#pragma once
// Physically consistent weighted least squares for any robot (identify --method pcls): the base
// parameters are K phi, phi the standard parameters of every link with its pseudo-inertia positive
// definite by construction (log-Cholesky, log_cholesky.hpp; Wensing et al. 2017, Rucker and Wensing
// 2022), the model's other parameters (friction, rotor inertia, offsets) free; maximum a posteriori
// with a Gaussian prior on phi centred on the robot file's nominal inertials, which decides only the
// directions of phi the data cannot see. Solved by Levenberg-Marquardt on the data compressed to
// its triangular factor (P rows, not the log's).

#include <Eigen/Core>
#include <vector>

namespace dyncal::host {

/// Relative standard deviation of the nominal (CAD) inertials in the prior: each standard
/// parameter within +-50 % (1 sigma) of max(|value|, 5 % of the largest of its kind in the link:
/// inertia, first moment, mass). Weak beside a log's thousands of samples on what they identify.
inline constexpr double kPriorRelativeStd = 0.5;

struct ConsistentProblem {
  Eigen::MatrixXd R;      ///< P x P upper triangular: R^T R = W^T W of the weighted data (StreamingLeastSquares)
  Eigen::VectorXd z;      ///< P: the rotated right-hand side, ||W p - y||^2 = ||R p - z||^2 + const
  int num_base = 0;       ///< the first num_base of the P model parameters are base parameters
  Eigen::MatrixXd K;      ///< num_base x 10 L: base parameters of the standard ones (Gautier)
  Eigen::VectorXd prior;  ///< 10 L nominal standard parameters (robot.json inertials)
  double prior_relative_std = kPriorRelativeStd;  ///< <= 0: no prior (consistency alone)
  double sigma2 = 1;      ///< variance of the weighted residual, for the parameters' standard deviations
  Eigen::VectorXd start;  ///< P: start of the non-inertial parameters (e.g. the WLS solution); empty: 0
};

struct ConsistentSolution {
  Eigen::VectorXd params;              ///< P model parameters (base ones = K standard)
  Eigen::VectorXd params_std;          ///< their standard deviations (Gauss-Newton at the solution, sigma2)
  Eigen::VectorXd standard;            ///< 10 L consistent standard parameters
  std::vector<double> min_eigenvalue;  ///< per link, of its pseudo-inertia (> 0: consistent)
  int iterations = 0;
};

/// Solves `p`. Throws InputError when Levenberg-Marquardt fails or ends non-finite.
ConsistentSolution consistent_least_squares(const ConsistentProblem& p);

/// Prior standard deviation of each of the 10 L standard parameters of `nominal` (see
/// kPriorRelativeStd); a kind that is zero in a link takes the robot's largest of that kind as its
/// scale (and 1 if zero everywhere).
Eigen::VectorXd prior_std(const Eigen::VectorXd& nominal, double relative_std);

}  // namespace dyncal::host
