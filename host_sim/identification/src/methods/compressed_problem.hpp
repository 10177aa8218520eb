#pragma once
// identify's search problem for the optimisers (private to host_sim/identification): any robot's
// weighted least-squares data compressed to their triangular factor (ConsistentProblem), the
// decision vector [10 L standard parameters | the model's other parameters], the latter profiled
// out (variable projection) so the search runs over the standard parameters alone.

#include "dyncal_host/identification/methods/consistent_least_squares.hpp"
#include "dyncal_host/identification/methods/search_problem.hpp"

namespace dyncal::host::detail {

class CompressedProblem : public SearchProblem {
 public:
  /// Throws InputError when p's shapes disagree or the other parameters' columns are rank deficient.
  CompressedProblem(const ConsistentProblem& p, double range_width);

  int groups() const override { return 1; }
  /// ||c2 - B2 phi||^2 / sigma2: the weighted residual's sum of squares (less its least-squares
  /// minimum) at phi with the other parameters at their best; its gradient in phi (0 in the others).
  double least_squares(const double* x, double* grad) const override;
  /// The other parameters at their least-squares values; one group: mean 0, var the cost (the
  /// compressed data carry the sum of squares only).
  Eigen::VectorXd with_fitted_amplitudes(const Eigen::VectorXd& x, std::vector<double>& mean,
                                         std::vector<double>& var) const override;
  double likelihood_scale() const override { return 0.5; }
  /// The consistent nominal values, the other parameters fitted.
  Eigen::VectorXd data_start() const override;
  /// A local search from x (the memetic step): gradient_search (CCSAQ) for kMemeticEvaluations cost
  /// evaluations. False when x is infeasible or the search found no feasible point.
  bool memetic_child(const Eigen::VectorXd& x, Eigen::VectorXd& child) const override;
  static constexpr int kMemeticEvaluations = 200;

  /// The model parameters p = [K phi; the others] of a decision vector.
  Eigen::VectorXd model_parameters(const Eigen::VectorXd& x) const;
  /// Free standard parameters at a range end that binds (ConsistentSolution::at_range_end).
  int at_range_end(const Eigen::VectorXd& x) const;

 private:
  int num_base_ = 0, others_ = 0;
  double inv_sigma2_ = 1;
  Eigen::MatrixXd K_;   // num_base x 10 L
  Eigen::MatrixXd B2_;  // (P - others) x 10 L: the base columns of R times K, in the others' complement
  Eigen::VectorXd c2_;  // z in that complement
  Eigen::MatrixXd B1_;  // others x 10 L: Q1^T R_b K
  Eigen::VectorXd c1_;  // Q1^T z
  Eigen::MatrixXd R1_;  // others x others, upper triangular: R_others = Q1 R1
};

}  // namespace dyncal::host::detail
