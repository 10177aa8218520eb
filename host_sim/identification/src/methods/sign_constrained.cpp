#include "dyncal_host/identification/methods/sign_constrained.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {
namespace {

/// Least-squares solution of R on the columns with free[i] (0 elsewhere), and diag((R_F^T R_F)^-1).
Eigen::VectorXd solve_free(const Eigen::MatrixXd& R, const Eigen::VectorXd& z, const std::vector<char>& free,
                           Eigen::VectorXd* inverse_gram_diag) {
  const Eigen::Index n = R.cols();
  std::vector<Eigen::Index> cols;
  for (Eigen::Index i = 0; i < n; ++i)
    if (free[static_cast<size_t>(i)]) cols.push_back(i);
  Eigen::MatrixXd A(R.rows(), static_cast<Eigen::Index>(cols.size()));
  for (size_t k = 0; k < cols.size(); ++k) A.col(static_cast<Eigen::Index>(k)) = R.col(cols[k]);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  if (cols.empty()) {
    if (inverse_gram_diag) *inverse_gram_diag = Eigen::VectorXd::Zero(n);
    return x;
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  if (qr.rank() < A.cols()) throw InputError("sign-constrained least squares: the regressor is rank deficient");
  const Eigen::VectorXd xf = qr.solve(z);
  for (size_t k = 0; k < cols.size(); ++k) x[cols[k]] = xf[static_cast<Eigen::Index>(k)];
  if (inverse_gram_diag) {
    const Eigen::MatrixXd inv = (A.transpose() * A).ldlt().solve(Eigen::MatrixXd::Identity(A.cols(), A.cols()));
    *inverse_gram_diag = Eigen::VectorXd::Zero(n);
    for (size_t k = 0; k < cols.size(); ++k)
      (*inverse_gram_diag)[cols[k]] = inv(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k));
  }
  return x;
}

}  // namespace

SignConstrainedSolution sign_constrained_least_squares(const Eigen::MatrixXd& R, const Eigen::VectorXd& z,
                                                       const std::vector<int>& nonnegative,
                                                       const Eigen::VectorXd& start) {
  const Eigen::Index n = R.cols();
  if (R.rows() < n || z.size() != R.rows() || start.size() != n)
    throw InputError("sign-constrained least squares: R must be m x n with m >= n, z m and the start n long");
  std::vector<char> constrained(static_cast<size_t>(n), 0);
  for (int i : nonnegative) {
    if (i < 0 || i >= n) throw InputError("sign-constrained least squares: index out of range");
    constrained[static_cast<size_t>(i)] = 1;
  }
  SignConstrainedSolution out;
  out.x = start;
  bool feasible = true;
  for (int i : nonnegative) feasible = feasible && start[i] >= 0;
  if (feasible) {
    solve_free(R, z, std::vector<char>(static_cast<size_t>(n), 1), &out.inverse_gram_diag);
    return out;
  }
  // Lawson-Hanson from a feasible point: the negative constrained values set to 0 and held.
  std::vector<char> free(static_cast<size_t>(n), 1);
  Eigen::VectorXd x = start;
  for (int i : nonnegative) {
    if (x[i] < 0) {
      x[i] = 0;
      free[static_cast<size_t>(i)] = 0;
    }
  }
  const double tol = 1e-12 * std::max(1.0, (R.transpose() * z).cwiseAbs().maxCoeff());
  const int max_iterations = 3 * static_cast<int>(n) + 10;
  Eigen::VectorXd s;
  for (;;) {
    // Inner loop: the least squares on the free set, stepped back to feasibility while it is not.
    for (;;) {
      if (++out.iterations > max_iterations)
        throw InputError("sign-constrained least squares: no convergence in " + std::to_string(max_iterations) +
                         " steps");
      s = solve_free(R, z, free, nullptr);
      double alpha = 1.0;
      for (Eigen::Index i = 0; i < n; ++i) {
        if (free[static_cast<size_t>(i)] && constrained[static_cast<size_t>(i)] && s[i] <= 0)
          alpha = std::min(alpha, x[i] / (x[i] - s[i]));
      }
      if (alpha >= 1.0) break;
      x += alpha * (s - x);
      for (Eigen::Index i = 0; i < n; ++i) {
        if (free[static_cast<size_t>(i)] && constrained[static_cast<size_t>(i)] && x[i] <= 0) {
          x[i] = 0;
          free[static_cast<size_t>(i)] = 0;
        }
      }
    }
    x = s;
    // The held index whose release lowers the cost most, if any (w = -gradient / 2).
    const Eigen::VectorXd w = R.transpose() * (z - R * x);
    Eigen::Index best = -1;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!free[static_cast<size_t>(i)] && w[i] > tol && (best < 0 || w[i] > w[best])) best = i;
    }
    if (best < 0) break;
    free[static_cast<size_t>(best)] = 1;
  }
  out.x = x;
  solve_free(R, z, free, &out.inverse_gram_diag);
  for (Eigen::Index i = 0; i < n; ++i)
    if (!free[static_cast<size_t>(i)]) out.held.push_back(static_cast<int>(i));
  out.residual_increase = std::max(0.0, (R * x - z).squaredNorm() - (R * start - z).squaredNorm());
  return out;
}

}  // namespace dyncal::host
