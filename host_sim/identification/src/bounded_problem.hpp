#pragma once
// What the three optimisers share (private to host_sim/identification): the objective over the free
// variables mapped to the unit box of their search ranges (linearly; logarithmically for the
// scale parameters: velocities and inverse velocities of the friction models), feasibility, and the Estimate of a
// solution. The inertial ranges are centred on the CAD values projected onto the physically consistent set, so the
// feasible part of the box is never empty.

#include <chrono>
#include <string>
#include <vector>

#include "dyncal_host/identification/optimisers.hpp"

namespace dyncal::host::detail {

class BoundedProblem {
 public:
  BoundedProblem(const RunData& data, FrictionModel model, const MethodSettings& settings,
                 const OptimiserSettings& options);

  int free_dimension() const { return static_cast<int>(free_.size()); }
  /// Full decision vector (TorqueObjective order) from unit coordinates u (free_dimension()).
  Eigen::VectorXd full(const double* u) const;
  /// Unit coordinates of a full decision vector (clamped into [0, 1]).
  Eigen::VectorXd unit(const Eigen::VectorXd& x) const;
  /// d x / d u of free variable k at x (the range width; x ln(hi / lo) for a scale parameter).
  double scale(int k, const Eigen::VectorXd& x) const;
  int free_index(int k) const { return free_[k]; }

  double eq25(const Eigen::VectorXd& x) const { return objective_.eq25(x.data(), options_.k_e); }
  /// x with each joint's friction amplitudes at their least-squares values given x's standard and
  /// scale parameters (TorqueObjective::fit_amplitudes), clamped into their ranges; the residual
  /// moments there into mean, var.
  Eigen::VectorXd with_fitted_amplitudes(const Eigen::VectorXd& x, std::array<double, 6>& mean,
                                         std::array<double, 6>& var) const;
  double k_e() const { return options_.k_e; }
  const TorqueObjective& objective() const { return objective_; }
  /// Sum over links of the relative negative part of lambda_min of the pseudo-inertia (0: feasible).
  double violation(const Eigen::VectorXd& x) const { return feasibility_violation(x.data(), cad_); }
  const Eigen::VectorXd& cad() const { return cad_; }

  /// The Estimate of a full decision vector: standard parameters as found, friction, tau_hat.
  Estimate estimate(const Eigen::VectorXd& x, const char* method, std::chrono::steady_clock::time_point t0,
                    int iterations) const;

 private:
  const RunData& data_;
  FrictionModel model_;
  MethodSettings settings_;
  OptimiserSettings options_;
  TorqueObjective objective_;
  SearchRanges ranges_;
  Eigen::VectorXd cad_;
  std::vector<int> free_;
  std::vector<bool> logarithmic_;  // per free variable
};

}  // namespace dyncal::host::detail
