#pragma once
// One compiled robot's identification model for one built term set (lib/ IdentificationModel<Robot,
// Terms>) as run-time data and operations. This is all the identification pipeline needs of a
// robot: the pipeline (identify_pipeline.hpp) is compiled once against it, and only what must be
// fixed-size per robot -- the generated regressor -- is compiled per robot and term set
// (term_set_model_of.hpp, in the robots' units). The least squares, KF and RLS run at the model's
// run-time size (recursive_fit.hpp).

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "dyncal/identification_model.hpp"
#include "dyncal/status.hpp"

namespace dyncal::host {

/// lib/ StreamingLeastSquares (IDIM-OLS / WLS, survey Eq. 15) of one model's size P behind a
/// run-time interface: the same updater, the same arithmetic (recursive_fit.hpp makes it).
class LeastSquaresFit {
 public:
  virtual ~LeastSquaresFit() = default;
  virtual void reset() = 0;
  /// One equation y = k^T phi (k: P entries) with weight w > 0.
  virtual UpdateStatus add_row(const double* k, double y, double w) = 0;
  /// Solution phi (resized to P); rank_deficient leaves phi unchanged.
  virtual UpdateStatus solve(Eigen::VectorXd& phi) const = 0;
  /// Diagonal of (W^T W)^-1 (P).
  virtual UpdateStatus inverse_gram_diagonal(Eigen::VectorXd& diag) const = 0;
  virtual double residual_sum_of_squares() const = 0;
  virtual long rows() const = 0;
  /// The triangular factor R (P x P, R^T R = W^T W) and the rotated right-hand side z (P).
  virtual Eigen::MatrixXd r_factor() const = 0;
  virtual Eigen::VectorXd rotated_rhs() const = 0;
};

/// lib/ KalmanFilter (survey Eq. 19) or RlsForgetting (Eq. 23) of one model's size behind a
/// run-time interface (recursive_fit.hpp makes them).
class RecursiveFit {
 public:
  virtual ~RecursiveFit() = default;
  /// One sample: K (N x P, column-major), tau (N) [Nm], and per joint the filter's noise input (KF:
  /// measurement variance [Nm^2]; RLS: weight 1 / sigma).
  virtual UpdateStatus update(const double* K, const double* tau, const double* noise) = 0;
  virtual Eigen::VectorXd estimate() const = 0;
  /// sqrt(diag P) (P).
  virtual Eigen::VectorXd covariance_diagonal() const = 0;
};

/// IdentificationModel<Robot, Terms> of one compiled robot at run time.
struct TermSetModel {
  unsigned terms = 0;  ///< dyncal::term bits of the built term set
  int num_joints = 0, num_params = 0, num_base = 0;
  std::vector<ParamInfo> info;     ///< P: IdentificationModel::info
  std::vector<std::string> names;  ///< P: base parameter names, then the terms' (e.g. Fc1), table order
  /// Per joint (0-based): the generated rotor_inertia_separate / rotor_inertia_absorbed_into (-1: the
  /// robot file declares no rotor inertia).
  std::vector<char> rotor_inertia_separate;
  std::vector<int> rotor_inertia_absorbed_into;

  /// K = IdentificationModel::regressor(q, qd, qdd, tau_load = 0) (N x P, column-major into K);
  /// q, qd, qdd: N joint values [rad, rad/s, rad/s^2].
  void (*regressor)(const double* q, const double* qd, const double* qdd, double* K) = nullptr;

  /// Column of term t of joint joint0 (0-based), or -1 (IdentificationModel::column).
  int column(unsigned t, int joint0) const {
    for (int i = num_base; i < num_params; ++i) {
      const ParamInfo& p = info[static_cast<size_t>(i)];
      if (p.term == t && p.joint == joint0 + 1) return i;
    }
    return -1;
  }
};

}  // namespace dyncal::host
