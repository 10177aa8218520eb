#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "finite.hpp"
#include "kalman_filter.hpp"
#include "robot_model.hpp"
#include "status.hpp"
#include "ud_covariance.hpp"

namespace dyncal {

/// Recursive payload identification with the arm's model fixed (docs/payload.md): a load rigidly
/// attached to the last link N changes only that link's 10 standard parameters dphi = [XX XY XZ YY
/// YZ ZZ MX MY MZ M] (link N's frame, about its origin; Khalil-Kleinfinger), so the torque beyond
/// the arm's model is
///
///   y = tau - tau_arm = Y_b(q, qd, qdd) K_N dphi,
///
/// K_N (b x 10) the base map's columns of link N (Gautier: phi_b = K phi), computed once from the
/// generated standard_to_base. dphi by the Kalman filter for constant parameters (survey Eq. 19,
/// KalmanFilter<Scalar, 10, N>); with a diffuse prior its estimate is the batch least-squares one.
/// tau_arm is the arm's feed-forward (the drive's active table, friction included).
///
/// Mass, centre of mass and inertia follow from dphi (m = M, c = [MX MY MZ] / m, I_c by the
/// parallel-axis theorem); the host does that with the standard deviations (payload.hpp).
///
/// The covariance is kept in UD factors (UdCovariance, Bierman) by default: a load's inertia has a
/// posterior variance some 1e12 below a diffuse prior's, beyond float's digits in the packed form
/// (which then reports not_positive_definite). Robot: a generated model (dyncal/robot_model.hpp).
/// Memory: K_N's 10 b scalars and the filter's (UD: 150 + 10 scalars); no heap, no exceptions. Every call returns a
/// status and leaves the state unchanged when it is not ok.
/// The size each payload parameter's verdict compares its 95 % half-width with (docs/payload.md
/// "Verdicts"): the mass |m| against itself, a first moment against m l, an inertia entry about the
/// link origin against m l^2, l = max(|c|, |c_N|) the payload's lever: c = [MX MY MZ] / M of
/// `dphi` (10: XX XY XZ YY YZ ZZ MX MY MZ M), c_N the last link's own centre of mass from its
/// standard parameters `link` (10, the robot file's: the size of the body the load is fixed to).
/// Writes `scale` (10) and returns l; a zero mass or lever gives zero scales (no load to judge).
template <typename Scalar>
Scalar payload_scales(const Eigen::Matrix<Scalar, 10, 1>& dphi, const Scalar* link,
                      Eigen::Matrix<Scalar, 10, 1>& scale) noexcept {
  using std::abs;
  using std::max;
  const Scalar m = abs(dphi[9]);
  const Scalar c = m > Scalar(0) ? Scalar(dphi.template segment<3>(6).norm() / m) : Scalar(0);
  const Scalar c_link =
      link[9] > Scalar(0) ? Scalar(Eigen::Matrix<Scalar, 3, 1>(link[6], link[7], link[8]).norm() / link[9]) : Scalar(0);
  const Scalar lever = max(c, c_link);
  for (int i = 0; i < 10; ++i) scale[i] = i < 6 ? m * lever * lever : (i < 9 ? m * lever : m);
  return lever;
}

template <class Robot, typename Scalar = double, class Covariance = UdCovariance<Scalar, 10>>
class PayloadEstimator {
  static_assert(is_robot_model_v<Robot>, "Robot must meet dyncal/robot_model.hpp");

 public:
  static constexpr int kJoints = Robot::kNumJoints;
  static constexpr int kBase = Robot::kNumBase;
  static constexpr int kParams = 10;
  using JointVector = Eigen::Matrix<Scalar, kJoints, 1>;
  using ParamVector = Eigen::Matrix<Scalar, kParams, 1>;
  using Regressor = Eigen::Matrix<Scalar, kJoints, kParams>;

  PayloadEstimator() noexcept {
    // K_N column by column: the base parameters of a unit change of each of link N's parameters.
    Eigen::Matrix<Scalar, Robot::kNumStandard, 1> unit = Eigen::Matrix<Scalar, Robot::kNumStandard, 1>::Zero();
    Eigen::Matrix<Scalar, kBase, 1> column;
    for (int i = 0; i < kParams; ++i) {
      unit[Robot::kNumStandard - kParams + i] = Scalar(1);
      Robot::standard_to_base(unit, column);
      link_map_.col(i) = column;
      unit[Robot::kNumStandard - kParams + i] = Scalar(0);
    }
  }

  /// Starts from no load (dphi = 0) with prior variance p0 per parameter (all > 0: a diffuse prior,
  /// e.g. 1e6 in the parameters' units, makes the estimate least squares'). rejected_non_finite,
  /// not_positive_definite (p0 <= 0) leave the estimator unchanged.
  UpdateStatus reset(const ParamVector& p0) noexcept {
    if (!all_finite(p0)) return UpdateStatus::rejected_non_finite;
    for (int i = 0; i < kParams; ++i)
      if (!(p0[i] > Scalar(0))) return UpdateStatus::not_positive_definite;
    return kf_.reset(ParamVector::Zero(), p0);
  }

  /// The payload regressor Y_b(q, qd, qdd) K_N (N x 10) at one state [rad, rad/s, rad/s^2].
  void regressor(const JointVector& q, const JointVector& qd, const JointVector& qdd, Regressor& Y) const noexcept {
    Eigen::Matrix<Scalar, kJoints, kBase> Yb;
    Robot::base_regressor(q, qd, qdd, Yb);
    regressor_from_base(Yb, Y);
  }
  /// The same from the base regressor Y_b (N x kBase) already evaluated at the state (a drive that
  /// has it for its feed-forward, the first kBase columns of IdentificationModel's regressor).
  template <class Derived>
  void regressor_from_base(const Eigen::MatrixBase<Derived>& Yb, Regressor& Y) const noexcept {
    Y.noalias() = Yb.lazyProduct(link_map_);  // coefficient-wise: no GEMM blocking buffers on the stack
  }
  /// One sample: the state and the torque the arm's model does not explain, residual = tau_measured
  /// - tau_arm [Nm] (N), with measurement variances r [Nm^2] (all > 0). rejected_non_finite,
  /// not_positive_definite and the filter's statuses leave the estimate unchanged.
  UpdateStatus update(const JointVector& q, const JointVector& qd, const JointVector& qdd, const JointVector& residual,
                      const JointVector& r) noexcept {
    if (!all_finite(q) || !all_finite(qd) || !all_finite(qdd)) return UpdateStatus::rejected_non_finite;
    Eigen::Matrix<Scalar, kJoints, kBase> Yb;
    Robot::base_regressor(q, qd, qdd, Yb);
    return update_base(Yb, residual, r);
  }
  /// update() from the base regressor Y_b at the state (N x kBase; see regressor_from_base): one
  /// regressor evaluation serves the feed-forward and the estimator, and no N x kBase copy is made.
  template <class Derived>
  UpdateStatus update_base(const Eigen::MatrixBase<Derived>& Yb, const JointVector& residual,
                           const JointVector& r) noexcept {
    if (!all_finite(residual) || !all_finite(r)) return UpdateStatus::rejected_non_finite;
    Regressor Y;
    regressor_from_base(Yb, Y);
    if (!all_finite(Y)) return UpdateStatus::rejected_non_finite;
    return kf_.update(Y, residual, r);
  }
  /// dphi [XX XY XZ YY YZ ZZ (kg m^2) MX MY MZ (kg m) M (kg)].
  const ParamVector& estimate() const noexcept { return kf_.estimate(); }
  /// The filter's variance of each parameter (its P's diagonal).
  void variance(ParamVector& out) const noexcept { kf_.covariance().diagonal(out); }

 private:
  Eigen::Matrix<Scalar, kBase, kParams> link_map_;
  KalmanFilter<Scalar, kParams, kJoints, Covariance> kf_;
};

}  // namespace dyncal
