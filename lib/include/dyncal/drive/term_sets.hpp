#pragma once
// The identification models a drive runs: one robot, the term sets (dyncal::term bits, survey Eq.
// 4-9 and 12) its parameter tables may carry. A table names its model by its model id; the drive
// checks it against that model (table_check.hpp) and computes the feed-forward of the control law
// with it (survey Fig. 3: tau_ff = [Y_b K_f](q_d, qd_d, qdd_d) phi, plus the table's effect terms).
// Heap-free, exception-free; the set is fixed at compile time (a drive maker lists what its
// firmware supports, each set compiles its own fixed-size regressor).

#include <Eigen/Core>
#include <cmath>
#include <cstdint>

#include "dyncal/effect_terms.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/parameter_table.hpp"
#include "dyncal/table_check.hpp"

namespace dyncal::drive {

/// The term sets `Terms...` of robot `Robot` (a generated model, robot_model.hpp): at least one,
/// the first the factory table's.
template <class Robot, unsigned... Terms>
struct TermSets {
  static_assert(sizeof...(Terms) >= 1, "a drive runs at least one model");
  using RobotType = Robot;
  static constexpr int kNumJoints = Robot::kNumJoints;
  static constexpr unsigned kTermSets[] = {Terms...};
  static constexpr int kCount = sizeof...(Terms);
  template <typename Scalar>
  using JointVector = Eigen::Matrix<Scalar, kNumJoints, 1>;

  /// Whether `model_id` is one of the term sets.
  static constexpr bool supports(std::uint32_t model_id) noexcept { return ((model_id == Terms) || ...); }

  /// check_table of the table's own model (wrong_robot first, wrong_model when the drive runs no
  /// such term set).
  static TableStatus check(const ParameterTable& t) noexcept {
    if (t.robot_id != Robot::kRobotId) return TableStatus::wrong_robot;
    TableStatus st = TableStatus::wrong_model;
    static_cast<void>(
        ((t.model_id == Terms ? (st = check_table<IdentificationModel<Robot, Terms>>(t), true) : false) || ...));
    return st;
  }
  /// As check(t), then the table's plausibility against the robot's ratings (table_check.hpp).
  static TableStatus check(const ParameterTable& t, const JointRatings<kNumJoints>& r) noexcept {
    if (t.robot_id != Robot::kRobotId) return TableStatus::wrong_robot;
    TableStatus st = TableStatus::wrong_model;
    static_cast<void>(
        ((t.model_id == Terms ? (st = check_table<IdentificationModel<Robot, Terms>>(t, r), true) : false) || ...));
    return st;
  }

  /// tau [Nm] = K(q, qd, qdd) phi of table `t` (which passed check) plus its effect terms
  /// (effect_terms.hpp): the inverse dynamics the table's model gives at joint-side q [rad], qd
  /// [rad/s], qdd [rad/s^2]. False (tau unchanged) for a model this drive does not run.
  template <typename Scalar>
  static bool torque(const ParameterTable& t, const JointVector<Scalar>& q, const JointVector<Scalar>& qd,
                     const JointVector<Scalar>& qdd, JointVector<Scalar>& tau) noexcept {
    return ((t.model_id == Terms ? (torque_of<Terms>(t, q, qd, qdd, tau), true) : false) || ...);
  }

  /// |Fc_j| [Nm] of table `t` per joint (0 where its model has no Coulomb column, or for a model
  /// this drive does not run).
  template <typename Scalar>
  static void coulomb(const ParameterTable& t, JointVector<Scalar>& fc) noexcept {
    fc.setZero();
    static_cast<void>(((t.model_id == Terms ? (coulomb_of<Terms>(t, fc), true) : false) || ...));
  }

 private:
  template <unsigned T, typename Scalar>
  static void coulomb_of(const ParameterTable& t, JointVector<Scalar>& fc) noexcept {
    using Model = IdentificationModel<Robot, T>;
    for (int j = 0; j < kNumJoints; ++j) {
      const int c = Model::column(term::coulomb, j);
      if (c >= 0 && c < t.count) fc[j] = static_cast<Scalar>(std::fabs(t.values[c]));
    }
  }

  template <unsigned T, typename Scalar>
  static void torque_of(const ParameterTable& t, const JointVector<Scalar>& q, const JointVector<Scalar>& qd,
                        const JointVector<Scalar>& qdd, JointVector<Scalar>& tau) noexcept {
    using Model = IdentificationModel<Robot, T>;
    typename Model::template Regressor<Scalar> K;
    Model::regressor(q, qd, qdd, JointVector<Scalar>::Zero().eval(), K);
    typename Model::template ParamVector<Scalar> phi;
    for (int i = 0; i < Model::kNumParams; ++i) phi[i] = static_cast<Scalar>(t.values[i]);
    tau = K * phi;
    if (t.effect_count == 0) return;
    const JointVector<Scalar> tau_rb = K.template leftCols<Robot::kNumBase>() * phi.template head<Robot::kNumBase>();
    add_effect_torques(t.effects, t.effect_count, q, qd, qdd, tau_rb, tau);
  }
};

}  // namespace dyncal::drive
