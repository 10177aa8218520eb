// Sign-constrained least squares (Lawson-Hanson with free variables): against the minimum over every
// active set on small random problems, its optimality conditions, and the unconstrained solution
// passed through untouched when it is feasible.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/sign_constrained.hpp"

namespace {

using dyncal::host::sign_constrained_least_squares;

struct Problem {
  Eigen::MatrixXd R;
  Eigen::VectorXd z, x0;
  std::vector<int> nonnegative;
};

/// A random problem: R (m x n) upper triangular with a spread of scales, z drawn so that the
/// unconstrained minimiser has about half of the constrained entries negative.
Problem random_problem(std::mt19937_64& rng, int m, int n, int constrained) {
  std::normal_distribution<double> N(0.0, 1.0);
  Problem p;
  p.R = Eigen::MatrixXd::Zero(m, n);
  for (int i = 0; i < n; ++i) {
    for (int j = i; j < n; ++j) p.R(i, j) = N(rng) * (i == j ? 3.0 : 1.0) * std::pow(10.0, (i % 3) - 1);
  }
  for (int i = n; i < m; ++i) {
    for (int j = 0; j < n; ++j) p.R(i, j) = N(rng);
  }
  p.z = Eigen::VectorXd::NullaryExpr(m, [&] { return N(rng); });
  p.x0 = p.R.colPivHouseholderQr().solve(p.z);
  for (int k = 0; k < constrained; ++k) p.nonnegative.push_back(n - constrained + k);
  return p;
}

/// The least cost over every choice of held indices whose free solution is feasible (the
/// constrained minimum lies on one of them).
double brute_force_minimum(const Problem& p) {
  const int c = static_cast<int>(p.nonnegative.size()), n = static_cast<int>(p.R.cols());
  double best = INFINITY;
  for (int mask = 0; mask < (1 << c); ++mask) {
    std::vector<int> free;
    for (int i = 0; i < n; ++i) {
      bool held = false;
      for (int k = 0; k < c; ++k) held = held || ((mask >> k) & 1 && p.nonnegative[static_cast<size_t>(k)] == i);
      if (!held) free.push_back(i);
    }
    Eigen::MatrixXd A(p.R.rows(), static_cast<Eigen::Index>(free.size()));
    for (size_t k = 0; k < free.size(); ++k) A.col(static_cast<Eigen::Index>(k)) = p.R.col(free[k]);
    const Eigen::VectorXd xf = A.colPivHouseholderQr().solve(p.z);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
    for (size_t k = 0; k < free.size(); ++k) x[free[k]] = xf[static_cast<Eigen::Index>(k)];
    bool feasible = true;
    for (int i : p.nonnegative) feasible = feasible && x[i] >= -1e-12;
    if (feasible) best = std::min(best, (p.R * x - p.z).squaredNorm());
  }
  return best;
}

TEST(SignConstrainedLeastSquares, ReachesTheMinimumOverEveryActiveSet) {
  std::mt19937_64 rng(11);
  int with_held = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Problem p = random_problem(rng, 14, 9, 6);
    const auto sol = sign_constrained_least_squares(p.R, p.z, p.nonnegative, p.x0);
    const double cost = (p.R * sol.x - p.z).squaredNorm();
    const double best = brute_force_minimum(p);
    ASSERT_NEAR(cost, best, 1e-9 * (1 + best)) << "trial " << trial;
    EXPECT_NEAR(sol.residual_increase, cost - (p.R * p.x0 - p.z).squaredNorm(), 1e-9 * (1 + best));
    // Optimality (KKT): feasible; held entries at 0 with a gradient that pushes outwards; free ones stationary.
    const Eigen::VectorXd g = 2 * p.R.transpose() * (p.R * sol.x - p.z);
    const double scale = 1e-8 * (1 + g.cwiseAbs().maxCoeff() + (p.R.transpose() * p.z).norm());
    for (int i : p.nonnegative) EXPECT_GE(sol.x[i], 0.0) << "trial " << trial << ", index " << i;
    std::vector<char> held(static_cast<size_t>(p.R.cols()), 0);
    for (int i : sol.held) {
      held[static_cast<size_t>(i)] = 1;
      EXPECT_EQ(sol.x[i], 0.0);
      EXPECT_GE(g[i], -scale) << "trial " << trial << ", held " << i;
      EXPECT_EQ(sol.inverse_gram_diag[i], 0.0);
    }
    for (Eigen::Index i = 0; i < p.R.cols(); ++i) {
      if (!held[static_cast<size_t>(i)]) {
        EXPECT_NEAR(g[i], 0.0, scale) << "trial " << trial << ", free " << i;
      }
    }
    with_held += !sol.held.empty();
  }
  EXPECT_GT(with_held, 150);  // the problems do exercise the constraints
}

TEST(SignConstrainedLeastSquares, AFeasibleStartIsReturnedUntouched) {
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    Problem p = random_problem(rng, 10, 6, 3);
    for (int i : p.nonnegative) p.x0[i] = std::abs(p.x0[i]);  // a feasible start (not the minimiser: kept as given)
    const auto sol = sign_constrained_least_squares(p.R, p.z, p.nonnegative, p.x0);
    EXPECT_TRUE(sol.held.empty());
    EXPECT_TRUE(sol.x == p.x0);
    EXPECT_EQ(sol.residual_increase, 0.0);
    const Eigen::MatrixXd inv = (p.R.transpose() * p.R).inverse();
    EXPECT_LT((sol.inverse_gram_diag - inv.diagonal()).cwiseAbs().maxCoeff(), 1e-9 * inv.diagonal().maxCoeff());
  }
}

TEST(SignConstrainedLeastSquares, RefusesBadInput) {
  const Eigen::MatrixXd R = Eigen::MatrixXd::Identity(3, 3);
  const Eigen::VectorXd z = Eigen::VectorXd::Ones(3);
  EXPECT_THROW(sign_constrained_least_squares(R, z, {3}, z), dyncal::host::InputError);
  EXPECT_THROW(sign_constrained_least_squares(R, Eigen::VectorXd::Ones(2), {0}, z), dyncal::host::InputError);
  Eigen::MatrixXd singular = R;
  singular(2, 2) = 0;
  EXPECT_THROW(sign_constrained_least_squares(singular, z, {0}, -z), dyncal::host::InputError);
}

}  // namespace
