// Drive-side acceptance of a parameter table for the identification model the drive runs.
#pragma once

#include <cmath>

#include "dyncal/identification_model.hpp"
#include "dyncal/parameter_table.hpp"

namespace dyncal {

/// Largest magnitude a table value may have (any parameter, SI units). Far above any physical
/// base parameter or friction coefficient of an arm, far below float overflow in the feed-forward.
inline constexpr float kTableMaxAbsValue = 1e5f;

/// Checks a decoded table against the drive's robot and model `Model` (an IdentificationModel):
/// robot id == Model::Robot::kRobotId, model id == Model::kTerms, count == Model::kNumParams,
/// every |value| <= kTableMaxAbsValue, and the dissipative and inertial terms (Coulomb, viscous,
/// rotor inertia) >= 0 (friction opposes motion, Eq. 3; inertia is positive). Returns the first
/// failing check; ok when the table may become active.
template <class Model>
TableStatus check_table(const ParameterTable& table) noexcept {
  if (table.robot_id != Model::RobotType::kRobotId) return TableStatus::wrong_robot;
  if (table.model_id != Model::kTerms || table.count != Model::kNumParams) return TableStatus::wrong_model;
  for (int i = 0; i < table.count; ++i) {
    const float v = table.values[i];
    if (!std::isfinite(v)) return TableStatus::non_finite;
    if (std::fabs(v) > kTableMaxAbsValue) return TableStatus::out_of_range;
    const ParamInfo info = Model::info(i);
    const bool non_negative =
        info.kind == ParamKind::term &&
        (info.term == term::coulomb || info.term == term::viscous || info.term == term::rotor_inertia);
    if (non_negative && v < 0.0f) return TableStatus::out_of_range;
  }
  if (table.effect_count > kTableMaxEffects) return TableStatus::bad_effect;
  for (int i = 0; i < table.effect_count; ++i) {
    const EffectTerm& e = table.effects[i];
    if (!effect_term_valid(e, Model::kNumJoints)) return TableStatus::bad_effect;
    for (float c : e.c)
      if (std::fabs(c) > kTableMaxAbsValue) return TableStatus::out_of_range;
  }
  return TableStatus::ok;
}

/// Per-joint ratings of the drive's robot (robot.json's limits, joint side, SI units), joint 1
/// first. A rating <= 0 (unknown) bounds nothing.
template <int N>
struct JointRatings {
  float tau_max[N];  ///< [Nm]
  float qd_max[N];   ///< [rad/s]
  float qdd_max[N];  ///< [rad/s^2]
  float q_min[N];    ///< [rad] position range (q_min == q_max: a full turn about 0)
  float q_max[N];    ///< [rad]
};

/// States of the rated envelope at which a table's rigid-body torque is checked.
inline constexpr int kRatedStates = 64;

/// The van der Corput radical inverse of i in `base`: the Halton sequence's coordinate, in [0, 1).
inline float radical_inverse(int i, int base) noexcept {
  float inv = 1.0f / static_cast<float>(base), f = inv, x = 0.0f;
  for (; i > 0; i /= base, f *= inv) x += f * static_cast<float>(i % base);
  return x;
}

/// State `index` (0 .. kRatedStates - 1) of the rated envelope: q in [q_min, q_max], |qd| <= qd_max,
/// |qdd| <= qdd_max, one Halton point (the first 3 N primes as bases, index + 1: the origin is
/// skipped) scaled to it. Deterministic and evenly spread: the same states on every drive.
template <int N, typename Vec>
void rated_state(const JointRatings<N>& r, int index, Vec& q, Vec& qd, Vec& qdd) noexcept {
  constexpr int kPrimes[21] = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73};
  static_assert(3 * N <= 21, "rated_state: at most 7 joints");
  for (int j = 0; j < N; ++j) {
    const float lo = r.q_min[j] < r.q_max[j] ? r.q_min[j] : -3.14159265f;
    const float hi = r.q_min[j] < r.q_max[j] ? r.q_max[j] : 3.14159265f;
    q[j] = lo + (hi - lo) * radical_inverse(index + 1, kPrimes[3 * j]);
    qd[j] = r.qd_max[j] * (2.0f * radical_inverse(index + 1, kPrimes[3 * j + 1]) - 1.0f);
    qdd[j] = r.qdd_max[j] * (2.0f * radical_inverse(index + 1, kPrimes[3 * j + 2]) - 1.0f);
  }
}

/// How many times a joint's tau_max one term of a table may demand at the joint's rated motion.
/// robot.json's tau_max may be a continuous rating or a scale derived from the nominal model
/// (docs/robots.md), and drives peak at two to three times their continuous rating: the shipped
/// ER20 stand-in's own viscous friction at qd_max is 1.6 tau_max on joint 6. Ten times is beyond
/// any drive, and the same bound the log loader applies to measured torques.
inline constexpr float kTableRatingMultiple = 10.0f;

/// check_table, then physical plausibility against the robot's own ratings: no per-joint term may
/// alone demand more than kTableRatingMultiple x the joint's tau_max at its rated motion —
/// |offset|, Fc; Fv qd_max; |Fp| qd_max^(1/3) (Eq. 8); Ia qdd_max —, nor may the rigid body, the
/// base parameters' torque Y_b(q, qd, qdd) phi_b (Gautier), at any of the kRatedStates states of the
/// rated envelope (rated_state). Such a table is a unit slip or a diverged fit (every value 1e5,
/// offsets of 1e5 Nm, base parameters 100 times the arm's). The states are samples: a table absurd
/// only between them passes (a lower bound of the torque's maximum over the envelope), a table within
/// the bound everywhere is never refused. Returns out_of_range for such a term (the first failing
/// check otherwise, as check_table). Host side (the simulated drive's commit): the rigid-body check
/// evaluates the base regressor kRatedStates times in float.
template <class Model>
TableStatus check_table(const ParameterTable& table, const JointRatings<Model::kNumJoints>& r) noexcept {
  const TableStatus st = check_table<Model>(table);
  if (st != TableStatus::ok) return st;
  for (int i = 0; i < table.count; ++i) {
    const ParamInfo info = Model::info(i);
    if (info.kind != ParamKind::term || info.joint < 1 || info.joint > Model::kNumJoints) continue;
    const int j = info.joint - 1;
    if (!(r.tau_max[j] > 0.0f)) continue;
    const float v = std::fabs(table.values[i]);
    float torque = 0.0f;  // the term's torque magnitude at the joint's rated motion [Nm]
    switch (info.term) {
      case term::offset:
      case term::coulomb:
        torque = v;
        break;
      case term::viscous:
        torque = v * r.qd_max[j];
        break;
      case term::power:
        torque = v * std::cbrt(r.qd_max[j]);
        break;
      case term::rotor_inertia:
        torque = v * r.qdd_max[j];
        break;
      default:
        continue;
    }
    if (torque > kTableRatingMultiple * r.tau_max[j]) return TableStatus::out_of_range;
  }
  using Robot = typename Model::RobotType;
  constexpr int N = Model::kNumJoints;
  using Vec = Eigen::Matrix<float, N, 1>;
  Eigen::Matrix<float, Robot::kNumBase, 1> phi_b;
  for (int i = 0; i < Robot::kNumBase; ++i) phi_b[i] = table.values[i];
  Eigen::Matrix<float, N, Robot::kNumBase> Yb;
  Vec q, qd, qdd;
  for (int s = 0; s < kRatedStates; ++s) {
    rated_state(r, s, q, qd, qdd);
    Robot::base_regressor(q, qd, qdd, Yb);
    const Vec tau = Yb * phi_b;
    for (int j = 0; j < N; ++j)
      if (r.tau_max[j] > 0.0f && std::fabs(tau[j]) > kTableRatingMultiple * r.tau_max[j])
        return TableStatus::out_of_range;
  }
  return TableStatus::ok;
}

/// Fills `table` from a parameter vector of Model (float32 values, model's column order).
template <class Model, typename Derived>
void make_table(const Eigen::MatrixBase<Derived>& phi, ParameterTable& table) noexcept {
  static_assert(Model::kNumParams <= kTableMaxParams, "model has more parameters than a table holds");
  table.robot_id = Model::RobotType::kRobotId;
  table.model_id = Model::kTerms;
  table.count = static_cast<std::uint16_t>(Model::kNumParams);
  for (int i = 0; i < Model::kNumParams; ++i) table.values[i] = static_cast<float>(phi[i]);
}

}  // namespace dyncal
