#pragma once
// The optimisation methods' objective (survey Sec. 3.4): the torque residual e = tau - K phi of every
// joint over a recorded run, reduced to per-joint sums so that one evaluation costs O(p^2) per joint
// instead of O(S p), exactly (no approximation): Eq. 25, J = sum_j |mean(e_j)| / sigma_j
// + k_e sum_j std(e_j) / sigma_j, and the least-squares cost sum_j ||e_j||^2 / (S sigma_j^2), both
// with their gradients. Also the search ranges and the physical feasibility the survey's optimisers
// work within.

#include <Eigen/Core>
#include <array>
#include <vector>

#include "dyncal_host/survey/survey_data.hpp"

namespace dyncal::host::survey {

/// Decision vector x = [60 standard parameters (Khalil-Kleinfinger order, link-major) | friction
/// joint-major]: Eq. 7 (Fc [Nm], beta [Nm s/rad]) per joint; Eq. 4 (Fc [Nm], Fs [Nm], qds [rad/s],
/// beta [Nm s/rad]) per joint with delta_s = 2.
class TorqueObjective {
 public:
  /// Throws InputError unless model is Eq. 7 or Eq. 4 and data has samples; sigma: per-joint weight
  /// (the assumed noise, Table 7) [Nm].
  TorqueObjective(const SurveyData& data, FrictionModel model, const std::array<double, 6>& sigma);

  FrictionModel model() const { return model_; }
  int friction_per_joint() const { return kf_; }
  int dimension() const;

  /// Mean and variance (population) of each joint's residual e_j / sigma_j at x, and, if the
  /// pointers are given, their gradients d/dx (6 x dimension(), row j for joint j).
  void residual_moments(const double* x, std::array<double, 6>& mean, std::array<double, 6>& var,
                        Eigen::MatrixXd* d_mean = nullptr, Eigen::MatrixXd* d_var = nullptr) const;

  /// Survey Eq. 25 on the sigma-weighted residuals; grad (dimension()) if not null.
  double eq25(const double* x, double k_e, double* grad = nullptr) const;
  /// sum_j (mean_j^2 + var_j) = sum_j ||e_j / sigma_j||^2 / S; grad if not null.
  double least_squares(const double* x, double* grad = nullptr) const;

 private:
  struct Joint {
    Eigen::MatrixXd G;             // 62 x 62: A^T A, A = [Y_j | sgn(qd_j) | qd_j] / sigma_j
    Eigen::VectorXd h, a;          // A^T tau, column sums of A
    double w = 1, tt = 0, ts = 0;  // 1 / sigma_j; tau^T tau, sum of tau (scaled)
    Eigen::MatrixXd A_sorted;      // Eq. 4: rows of A by increasing |qd|  (S x 62)
    Eigen::VectorXd tau_sorted, qd_sorted;
  };
  FrictionModel model_;
  int kf_ = 2;
  double n_ = 0;
  std::array<Joint, 6> joints_;
};

/// Box [lo, hi] of every decision variable. Inertial: the CAD value +- width x |CAD value| (a
/// structural zero stays fixed at 0). Friction, from the run itself (what a user can state without
/// knowing the answer): Fc, Fs in [0, max |tau_j|]; beta in [0, max |tau_j| / max |qd_j|]; qds in
/// [0.01, 1] x max |qd_j| (at least 1e-3 rad/s).
struct SearchRanges {
  Eigen::VectorXd lo, hi;
  bool fixed(int i) const { return lo[i] == hi[i]; }
};
SearchRanges search_ranges(const SurveyData& data, FrictionModel model, const Eigen::VectorXd& cad, double width);

/// Range of the Stribeck velocity qds of joint j (0-based) that search_ranges uses:
/// [max(1e-3, 0.01 max |qd_j|), max |qd_j|] [rad/s].
std::array<double, 2> stribeck_velocity_range(const SurveyData& data, int j);

/// Eq. 4 friction of every joint fitted to its residual tau_j - Y_j phi (phi: 60 standard
/// parameters), a start for the nonlinear solvers that uses no set value: qds from 64 log-spaced
/// values over stribeck_velocity_range, and at each Fc, Fs - Fc, beta by linear least squares
/// (variable projection, Golub and Pereyra 1973); the qds with the least squared residual wins.
/// Joint-major (Fc, Fs, qds, beta).
std::vector<double> stribeck_start(const SurveyData& data, const Eigen::VectorXd& phi);

/// Physical feasibility (Wensing et al. 2017): each link's pseudo-inertia positive definite.
/// Returns sum over links of max(0, -lambda_min(J_l)) / ||J_l(cad)||_F (0: feasible), and each
/// link's lambda_min if `lambda_min` is given.
double feasibility_violation(const double* x, const Eigen::VectorXd& cad, std::array<double, 6>* lambda_min = nullptr);

/// d lambda_min(J_l) / d phi_l (10) at link l's standard parameters (the eigenvector's quadratic
/// form on the pseudo-inertia's linear map); lambda returned.
double pseudo_inertia_min_eigenvalue(const double* phi10, double* gradient10);

}  // namespace dyncal::host::survey
