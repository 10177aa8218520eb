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

#include "dyncal_host/identification/methods/friction_fit.hpp"
#include "dyncal_host/model/inertial_parameters.hpp"
#include "dyncal_host/survey/methods/run_data.hpp"

namespace dyncal::host {

/// Decision vector x = [60 standard parameters (Khalil-Kleinfinger order, link-major) | friction
/// joint-major in friction_parameter_names order] for any of the six models (Eq. 4-9; Eq. 4 with
/// delta_s = 2, Eq. 9 with RunData::tau_load as the load torque).
class TorqueObjective {
 public:
  /// Throws InputError unless data has samples; sigma: per-joint weight (the assumed noise,
  /// Table 7) [Nm].
  TorqueObjective(const RunData& data, FrictionModel model, const std::array<double, 6>& sigma);

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

  /// Sets, in x, each joint's friction amplitudes (every parameter but the scale parameters: the
  /// friction is linear in them once the scales are fixed) to their least-squares values given the
  /// standard parameters and scale parameters in x (separable least squares, Golub and Pereyra
  /// 1973), exactly, from the same reduced sums; then clamps each into [lo[i], hi[i]] (full
  /// decision-vector bounds, if given). With mean and var, also the residual moments at the result,
  /// at no further pass over the samples.
  void fit_amplitudes(double* x, const double* lo = nullptr, const double* hi = nullptr,
                      std::array<double, 6>* mean = nullptr, std::array<double, 6>* var = nullptr) const;
  /// fit_amplitudes of every decision vector in xs (each dimension() long), joint by joint over the
  /// batch so that a joint's samples are read from cache; each vector's result is bit-identical to
  /// fit_amplitudes(xs[i], ...). mean, var (if given) are resized to xs.size().
  void fit_amplitudes(const std::vector<double*>& xs, const double* lo, const double* hi,
                      std::vector<std::array<double, 6>>* mean, std::vector<std::array<double, 6>>* var) const;
  /// Eq. 25 and the least-squares cost from residual moments (as eq25, least_squares).
  static double eq25_of(const std::array<double, 6>& mean, const std::array<double, 6>& var, double k_e);
  static double least_squares_of(const std::array<double, 6>& mean, const std::array<double, 6>& var);

 private:
  /// One joint's data. The friction parameters with a fixed column (is_linear_parameter) join the
  /// standard parameters in A = [Y_j | columns] / sigma_j, reduced to sums; the rest of the friction
  /// (the nonlinear part) is evaluated on the rows sorted by |qd|, only those below its reach for
  /// Eq. 4 (exp(-(qd / qds)^2) < 1e-18 beyond 6.5 qds), all rows for Eq. 5 and 6.
  struct Joint {
    int first = 0;                 // first standard column joint j's torque depends on
    Eigen::MatrixXd G;             // A^T A
    Eigen::VectorXd h, a;          // A^T tau, column sums of A
    double w = 1, tt = 0, ts = 0;  // 1 / sigma_j; tau^T tau, sum of tau (scaled)
    Eigen::MatrixXd A_sorted;      // nonlinear models: columns first.. of A, rows by |qd|
    Eigen::ArrayXd tau_sorted, qd_sorted, aq_sorted, sg_sorted, inv_aq_sorted;
  };
  /// Weighted nonlinear part n of rows [0, k) of joint J and, if dn is not null, dn / d theta (k x kf).
  void nonlinear_part(const Joint& J, const double* theta, Eigen::Index k, Eigen::ArrayXd& n,
                      Eigen::ArrayXXd* dn) const;
  Eigen::Index reach(const Joint& J, const double* theta) const;
  /// The nonlinear part's columns d n / d amplitude on rows [0, k) of joint J into D (k x kf; only the
  /// columns of nonlinear_amplitudes_ are set): what separable least squares needs of it.
  void amplitude_columns(const Joint& J, const double* theta, Eigen::Index k, Eigen::ArrayXXd& D) const;
  /// fit_amplitudes' work buffers, reused from one joint and vector to the next.
  struct AmplitudeScratch {
    Eigen::ArrayXXd D;
    Eigen::VectorXd r, n, r_left, z;
  };
  /// fit_amplitudes of joint j alone (its amplitudes in x; its mean and variance if both given).
  void fit_joint_amplitudes(int j, double* x, const double* lo, const double* hi, double* mean, double* var,
                            AmplitudeScratch& scratch) const;

  FrictionModel model_;
  int kf_ = 2;
  std::vector<int> linear_;                // friction parameters (per joint) with a fixed column, in column order
  std::vector<int> amplitudes_;            // friction parameters that are not scale parameters
  std::vector<int> amplitude_column_;      // each amplitude's column in A (kStandard + its linear_ index), -1: none
  std::vector<int> nonlinear_amplitudes_;  // indices into amplitudes_ of those with a nonlinear column
  double n_ = 0;
  std::array<Joint, 6> joints_;
};

/// Box [lo, hi] of every decision variable. Inertial: the CAD value +- width x |CAD value| (a
/// structural zero stays fixed at 0). Friction, from the run itself (what a user can state without
/// knowing the answer), with tau_j = max |tau_j| and v_j = max |qd_j|: Coulomb-like levels (Fc, Fs,
/// f1) in [0, tau_j]; the other amplitudes (f2, f4 of Eq. 5, f2 of Eq. 6) in [-tau_j, tau_j]; beta
/// in [0, tau_j / v_j]; fp in [-1, 1] tau_j / v_j^(1/3); fl in [0, 1]; velocity scales (qds, f3 of
/// Eq. 5) in velocity_scale_range, inverse ones (f5 of Eq. 5, f3 and f4 of Eq. 6) in its inverse.
struct SearchRanges {
  Eigen::VectorXd lo, hi;
  bool fixed(int i) const { return lo[i] == hi[i]; }
};
SearchRanges search_ranges(const RunData& data, FrictionModel model, const Eigen::VectorXd& cad, double width);

/// velocity_scale_range of joint j (0-based) of a run.
std::array<double, 2> velocity_scale_range(const RunData& data, int j);

/// The friction of every joint fitted to its residual tau_j - Y_j phi (phi: 60 standard
/// parameters) by fit_joint_friction, a start for the solvers that uses no set value, each parameter
/// clamped into its search range. Joint-major, friction_parameter_names order. Each joint's scale
/// parameter intervals (fit_joint_friction) into `intervals` (6 entries) if given.
std::vector<double> friction_start(const RunData& data, FrictionModel model, const Eigen::VectorXd& phi,
                                   std::vector<std::vector<ScaleInterval>>* intervals = nullptr);

/// Physical feasibility (Wensing et al. 2017): each link's pseudo-inertia positive definite.
/// Returns sum over links of max(0, -lambda_min(J_l)) / ||J_l(cad)||_F (0: feasible), and each
/// link's lambda_min if `lambda_min` is given.
double feasibility_violation(const double* x, const Eigen::VectorXd& cad, std::array<double, 6>* lambda_min = nullptr);

}  // namespace dyncal::host
