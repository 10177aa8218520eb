#pragma once

#include <Eigen/Core>

#include "finite.hpp"
#include "momentum_observer.hpp"
#include "parameter_table.hpp"
#include "robot_model.hpp"
#include "status.hpp"

namespace dyncal {

/// The direct residual, the comparison the generalised-momentum observer is measured against
/// (Haddadin, De Luca and Albu-Schaeffer 2017, Sec. 4: "direct estimation" from the inverse
/// dynamics): the external joint torque the calibrated model attributes to the sample,
///
///   e = M(q) qdd + n(q, qd) - tau   (tau the applied torque; the sign of the observer's r),
///
/// low-passed as the observer's residual is, r_k = (1 - K dt) r_{k-1} + K dt e_k: per joint a
/// first-order filter of the external torque with gain K [1/s]. Unlike the observer it needs the
/// joint acceleration qdd, which an encoder gives only by differentiating twice (CentredSlope's
/// parabola: its noise sqrt(15) / (D dt) times the velocity's), and M qdd carries that noise into e.
///
/// The model (M, n, the table's friction, offsets and effects) is the observer's
/// (MomentumObserver::model: the same table, the same checks). Units: q [rad], qd [rad/s], qdd
/// [rad/s^2], tau and r [Nm]. Memory: a MomentumObserver and two N-vectors; no heap, no
/// exceptions; every call returns a status and leaves the state unchanged unless ok.
template <class Robot, typename Scalar = double>
class DirectResidual {
 public:
  using Model = MomentumObserver<Robot, Scalar>;
  using JointVector = typename Model::JointVector;
  using MassMatrix = typename Model::MassMatrix;

  /// As MomentumObserver::configure (the same refusals: another robot's table, Eq. 9's load
  /// column, a wrong count, an invalid effect, K dt outside (0, 1], NaN).
  UpdateStatus configure(const ParameterTable& table, const JointVector& gain, Scalar dt) noexcept {
    const UpdateStatus st = model_.configure(table, gain, dt);
    if (st != UpdateStatus::ok) return st;
    gain_ = gain;
    dt_ = dt;
    residual_.setZero();
    return UpdateStatus::ok;
  }

  /// The next update() starts the filter again from r = 0.
  void restart() noexcept { residual_.setZero(); }

  /// One sample: q, qd, the friction terms' velocity qd_friction (qd with 0 inside a standstill
  /// band), qdd and the applied torque tau. rejected_non_finite on a non-finite input or result;
  /// invalid_argument before configure().
  UpdateStatus update(const JointVector& q, const JointVector& qd, const JointVector& qd_friction,
                      const JointVector& qdd, const JointVector& tau) noexcept {
    if (!(dt_ > Scalar(0))) return UpdateStatus::invalid_argument;
    if (!all_finite(q) || !all_finite(qd) || !all_finite(qd_friction) || !all_finite(qdd) || !all_finite(tau))
      return UpdateStatus::rejected_non_finite;
    MassMatrix M;
    JointVector n;
    model_.model(q, qd, qd_friction, M, n);
    const JointVector e = M * qdd + n - tau;
    if (!all_finite(e)) return UpdateStatus::rejected_non_finite;
    for (int j = 0; j < Model::kJoints; ++j) residual_[j] += gain_[j] * dt_ * (e[j] - residual_[j]);
    return UpdateStatus::ok;
  }

  /// The filtered residual r [Nm] after the last update (N; 0 before the first).
  const JointVector& residual() const noexcept { return residual_; }

 private:
  Model model_;
  JointVector gain_ = JointVector::Zero(), residual_ = JointVector::Zero();
  Scalar dt_ = Scalar(0);
};

}  // namespace dyncal
