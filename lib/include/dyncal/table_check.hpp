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
