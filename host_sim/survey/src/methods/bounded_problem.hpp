#pragma once
// The survey study's search problem (private to host_sim/survey): the er20's RunData with
// a friction model of Eq. 4-9, decision vector [60 standard parameters | friction joint-major] in
// TorqueObjective's order, the inertial ranges centred on the CAD values projected onto the
// physically consistent set (search_ranges), six groups (joints), and the Estimate of a solution.

#include <chrono>
#include <string>
#include <vector>

#include "dyncal_host/identification/methods/search_problem.hpp"
#include "dyncal_host/survey/methods/optimisers.hpp"

namespace dyncal::host::detail {

class BoundedProblem : public SearchProblem {
 public:
  BoundedProblem(const RunData& data, FrictionModel model, const MethodSettings& settings,
                 const OptimiserSettings& options);

  double eq25(const Eigen::VectorXd& x) const { return objective_.eq25(x.data(), options_.k_e); }
  double k_e() const { return options_.k_e; }
  const TorqueObjective& objective() const { return objective_; }

  int groups() const override { return 6; }
  double least_squares(const double* x, double* grad) const override { return objective_.least_squares(x, grad); }
  /// Each joint's friction amplitudes at their least-squares values given x's standard and scale
  /// parameters (TorqueObjective::fit_amplitudes), clamped into their ranges.
  Eigen::VectorXd with_fitted_amplitudes(const Eigen::VectorXd& x, std::vector<double>& mean,
                                         std::vector<double>& var) const override;
  /// The same for a population, joint by joint (TorqueObjective's batch fit_amplitudes).
  void fit_population(std::vector<Eigen::VectorXd>& xs, std::vector<std::vector<double>>& means,
                      std::vector<std::vector<double>>& vars) const override;
  /// S / 2: the assumed noise (MethodSettings::sigma) normalises the residual.
  double likelihood_scale() const override { return 0.5 * static_cast<double>(data_.q.rows()); }
  /// The consistent CAD values and each joint's friction_start (scale parameters from a log-grid scan).
  Eigen::VectorXd data_start() const override;
  std::vector<std::vector<int>> scale_groups() const override;
  /// Nonlinear models: x's friction, joint by joint, replaced by friction_start's scan at x's own
  /// inertial parameters where that lowers the joint's term of the cost (options' objective).
  bool memetic_child(const Eigen::VectorXd& x, Eigen::VectorXd& child) const override;

  /// The Estimate of a full decision vector: standard parameters as found, friction, tau_hat.
  Estimate estimate(const Eigen::VectorXd& x, const char* method, std::chrono::steady_clock::time_point t0,
                    int iterations) const;

 private:
  double joint_cost(double mean, double var) const;

  const RunData& data_;
  FrictionModel model_;
  MethodSettings settings_;
  OptimiserSettings options_;
  TorqueObjective objective_;
};

}  // namespace dyncal::host::detail
