#pragma once

#include <Eigen/Core>
#include <cmath>

#include "effect_terms.hpp"
#include "finite.hpp"
#include "friction.hpp"
#include "parameter_table.hpp"
#include "robot_model.hpp"
#include "status.hpp"

namespace dyncal {

/// The generalised-momentum observer (De Luca and Mattone 2003; Haddadin, De Luca and
/// Albu-Schaeffer 2017, Sec. 4) driven by a calibrated model: with the generalised momentum
/// p = M(q) qd, the arm obeys dp/dt = tau - n(q, qd) + dM/dt qd + tau_ext, n = C qd + g + tau_f
/// (-n + dM/dt qd = C^T qd - g - tau_f), and the residual
///
///   r = K (p - p(0) - integral(tau - n + dM/dt qd + r) dt)
///
/// follows dr/dt = K (tau_ext - r): per joint a first-order low-pass of the external joint torque
/// with gain K [1/s] (time constant 1 / K), from q and qd alone (no acceleration).
///
/// The model is a drive's parameter table (parameter_table.hpp): its base parameters (model_id's
/// term columns after them, IdentificationModel's order) and effect terms. M(q) is the generated
/// mass matrix of a standard-parameter vector with the table's base parameters (each base parameter
/// of Gautier's grouping has a standard parameter of its own with coefficient 1: that one takes the
/// value, the grouped ones 0; the dynamics depend on the base parameters alone) plus the table's
/// constant inertia terms (separate rotor inertia, the rotor_inertia and coupling effects); n is the
/// generated inverse dynamics at qdd = 0 plus the friction and offset columns and the effects at
/// qdd = 0 (load friction on the rigid body's torque without its inertial part, which the observer
/// cannot know).
///
/// Discrete time (sample period dt): the integral by the trapezoidal rule, dM/dt qd over a step as
/// (M_k - M_{k-1}) (qd_k + qd_{k-1}) / 2, so that p_k - p_{k-1} - that term is (M_k + M_{k-1}) / 2
/// (qd_k - qd_{k-1}) exactly: the residual integrates velocity increments and never differentiates
/// them; r_k = (1 - K dt) r_{k-1} + K (the step's external impulse), stable and without overshoot
/// for 0 < K dt <= 1.
///
/// Units: q [rad], qd [rad/s], tau and r [Nm] (joint side). Robot: a generated model
/// (robot_model.hpp). Memory: the standard parameters (10 N), M_{k-1} (N x N) and five N-vectors;
/// no heap, no exceptions. Every call returns a status and leaves the state unchanged when it is not
/// ok.
template <class Robot, typename Scalar = double>
class MomentumObserver {
  static_assert(is_robot_model_v<Robot>, "Robot must meet dyncal/robot_model.hpp");

 public:
  static constexpr int kJoints = Robot::kNumJoints;
  using JointVector = Eigen::Matrix<Scalar, kJoints, 1>;
  using MassMatrix = Eigen::Matrix<Scalar, kJoints, kJoints>;

  /// Takes the model of `table` and the gains K (N, [1/s]) for samples dt [s] apart; the next
  /// update() starts the observer. invalid_argument: a table of another robot, a model with a term
  /// the observer cannot split (Eq. 9's load column: tables carry load friction as an effect), a
  /// parameter count that is not the model's, an invalid effect, a generated model whose base
  /// parameters are not a grouping (no standard parameter of their own), K dt outside (0, 1];
  /// rejected_non_finite: a non-finite value. The observer is unchanged unless ok.
  UpdateStatus configure(const ParameterTable& table, const JointVector& gain, Scalar dt) noexcept {
    if (!all_finite(gain) || !std::isfinite(dt)) return UpdateStatus::rejected_non_finite;
    for (int j = 0; j < kJoints; ++j) {
      if (!(gain[j] > Scalar(0)) || !(gain[j] * dt <= Scalar(1))) return UpdateStatus::invalid_argument;
    }
    if (table.robot_id != Robot::kRobotId || (table.model_id & term::load) != 0u ||
        (table.model_id & ~((1u << kNumTerms) - 1u)) != 0u || table.count != num_params(table.model_id) ||
        table.effect_count > kTableMaxEffects)
      return UpdateStatus::invalid_argument;
    for (int i = 0; i < table.count; ++i)
      if (!std::isfinite(table.values[i])) return UpdateStatus::rejected_non_finite;
    for (int i = 0; i < table.effect_count; ++i)
      if (!effect_term_valid(table.effects[i], kJoints)) return UpdateStatus::invalid_argument;
    StandardVector phi = StandardVector::Zero();
    if (!standard_of_base(table.values, phi)) return UpdateStatus::invalid_argument;
    MassMatrix constant_inertia = MassMatrix::Zero();
    int col = Robot::kNumBase;
    for (int j = 0; j < kJoints; ++j) {
      for (int t = 0; t < kNumTerms; ++t) {
        if (!has_column(table.model_id, term_bit(t), j)) continue;
        if (term_bit(t) == term::rotor_inertia) constant_inertia(j, j) += Scalar(table.values[col]);
        ++col;
      }
    }
    // The effects' inertial part: their torque is affine in qdd with q-independent coefficients
    // (rotor inertia c0, a coupled motor's c2 on a = qdd_i + r qdd_j), so columns of unit qdd at rest.
    const JointVector zero = JointVector::Zero();
    JointVector at_rest = zero, unit_column;
    add_effect_torques(table.effects, table.effect_count, zero, zero, zero, zero, at_rest);
    for (int k = 0; k < kJoints; ++k) {
      unit_column.setZero();
      JointVector qdd = zero;
      qdd[k] = Scalar(1);
      add_effect_torques(table.effects, table.effect_count, zero, zero, qdd, zero, unit_column);
      constant_inertia.col(k) += unit_column - at_rest;
    }
    table_ = table;
    phi_ = phi;
    constant_inertia_ = constant_inertia;
    gain_ = gain;
    dt_ = dt;
    started_ = false;
    residual_.setZero();
    return UpdateStatus::ok;
  }

  /// The next update() starts the observer again (p-hat = p, r = 0): after a pause in the samples.
  void restart() noexcept {
    started_ = false;
    residual_.setZero();
  }

  /// One sample: q [rad], qd [rad/s], the joint torque the drive applied tau [Nm]. The first sample
  /// after configure()/restart() starts the observer with r = 0. rejected_non_finite on a
  /// non-finite input or result (state unchanged); invalid_argument before configure().
  UpdateStatus update(const JointVector& q, const JointVector& qd, const JointVector& tau) noexcept {
    return update(q, qd, qd, tau);
  }
  /// As above with the friction terms at their own velocity qd_friction [rad/s]: qd with 0 inside a
  /// standstill band, say (a measured velocity's sign flickers with its noise at rest, and the
  /// model's Coulomb torque with it; docs/monitor.md).
  UpdateStatus update(const JointVector& q, const JointVector& qd, const JointVector& qd_friction,
                      const JointVector& tau) noexcept {
    if (!(dt_ > Scalar(0))) return UpdateStatus::invalid_argument;
    if (!all_finite(q) || !all_finite(qd) || !all_finite(qd_friction) || !all_finite(tau))
      return UpdateStatus::rejected_non_finite;
    MassMatrix M;
    JointVector n;
    model(q, qd, qd_friction, M, n);
    const JointVector p = M * qd;
    if (!all_finite(M) || !all_finite(n)) return UpdateStatus::rejected_non_finite;
    if (!started_) {
      p_hat_ = p;
      residual_.setZero();
    } else {
      const JointVector qd_mid = Scalar(0.5) * (qd + qd_prev_);
      const JointVector p_hat =
          p_hat_ + dt_ * (Scalar(0.5) * (tau - n + force_prev_) + residual_) + (M - M_prev_) * qd_mid;
      const JointVector r = gain_.cwiseProduct(p - p_hat);
      if (!all_finite(r)) return UpdateStatus::rejected_non_finite;
      p_hat_ = p_hat;
      residual_ = r;
    }
    started_ = true;
    M_prev_ = M;
    qd_prev_ = qd;
    force_prev_ = tau - n;
    return UpdateStatus::ok;
  }

  /// The residual r [Nm] after the last update (N; 0 before the second sample).
  const JointVector& residual() const noexcept { return residual_; }
  const JointVector& gain() const noexcept { return gain_; }

  /// The model split tau = M(q) qdd + n(q, qd) of the configured table (M: N x N [kg m^2], n [Nm]).
  void model(const JointVector& q, const JointVector& qd, MassMatrix& M, JointVector& n) const noexcept {
    model(q, qd, qd, M, n);
  }
  /// The same with the friction terms at qd_friction.
  void model(const JointVector& q, const JointVector& qd, const JointVector& qd_friction, MassMatrix& M,
             JointVector& n) const noexcept {
    Robot::mass_matrix(q, phi_, M);
    M += constant_inertia_;
    const JointVector zero = JointVector::Zero();
    JointVector n_rb;
    Robot::inverse_dynamics(q, qd, zero, phi_, n_rb);
    n = n_rb;
    int col = Robot::kNumBase;
    for (int j = 0; j < kJoints; ++j) {
      for (int t = 0; t < kNumTerms; ++t) {
        const unsigned b = term_bit(t);
        if (!has_column(table_.model_id, b, j)) continue;
        if (b != term::rotor_inertia)
          n[j] += Scalar(table_.values[col]) * term_column(b, qd_friction[j], Scalar(0), Scalar(0));
        ++col;
      }
    }
    add_effect_torques(table_.effects, table_.effect_count, q, qd_friction, zero, n_rb, n);
  }

 private:
  using StandardVector = Eigen::Matrix<Scalar, Robot::kNumStandard, 1>;
  using BaseVector = Eigen::Matrix<Scalar, Robot::kNumBase, 1>;

  /// IdentificationModel's rule: term t has a column on joint j when the model has it, rotor
  /// inertia only where it is separately identifiable.
  static constexpr bool has_column(unsigned model, unsigned t, int j) {
    return (model & t) != 0u && (t != term::rotor_inertia || Robot::rotor_inertia_separate(j));
  }
  static constexpr int num_params(unsigned model) {
    int count = Robot::kNumBase;
    for (int j = 0; j < kJoints; ++j)
      for (int t = 0; t < kNumTerms; ++t) count += has_column(model, term_bit(t), j) ? 1 : 0;
    return count;
  }

  /// Standard parameters with the base parameters `base` (the first kNumBase of the table): for
  /// each base parameter the standard parameter that maps to it alone with coefficient 1. False
  /// when one has none.
  static bool standard_of_base(const float* base, StandardVector& phi) noexcept {
    StandardVector unit = StandardVector::Zero();
    BaseVector column;
    bool assigned[Robot::kNumBase] = {};
    int found = 0;
    for (int i = 0; i < Robot::kNumStandard; ++i) {
      unit[i] = Scalar(1);
      Robot::standard_to_base(unit, column);
      unit[i] = Scalar(0);
      int k = -1;
      bool single = true;
      for (int b = 0; b < Robot::kNumBase; ++b) {
        if (column[b] == Scalar(0)) continue;
        if (k >= 0 || column[b] != Scalar(1)) single = false;
        k = b;
      }
      if (!single || k < 0 || assigned[k]) continue;
      assigned[k] = true;
      phi[i] = Scalar(base[k]);
      ++found;
    }
    return found == Robot::kNumBase;
  }

  ParameterTable table_{};
  StandardVector phi_ = StandardVector::Zero();
  MassMatrix constant_inertia_ = MassMatrix::Zero();
  MassMatrix M_prev_ = MassMatrix::Zero();
  JointVector gain_ = JointVector::Zero(), residual_ = JointVector::Zero(), p_hat_ = JointVector::Zero();
  JointVector qd_prev_ = JointVector::Zero(), force_prev_ = JointVector::Zero();
  Scalar dt_ = Scalar(0);
  bool started_ = false;
};

}  // namespace dyncal
