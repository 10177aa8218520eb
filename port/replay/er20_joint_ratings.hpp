#pragma once
// The er20's ratings as the firmware's flash parameter store takes them (JointRatings), from the
// generated er20_ratings.hpp (robots/er20/robot.json's limits, joint side).
#include "dyncal/table_check.hpp"
#include "er20_ratings.hpp"

namespace dyncal::replay {

/// The er20's ratings (robots/er20/robot.json's limits, joint side; er20_ratings.hpp) as the flash
/// parameter store checks tables against them.
inline JointRatings<6> ratings() {
  JointRatings<6> r;
  for (int j = 0; j < 6; ++j) {
    r.tau_max[j] = data::kTauMax[j];
    r.qd_max[j] = data::kQdMax[j];
    r.qdd_max[j] = data::kQddMax[j];
    r.q_min[j] = data::kQMin[j];
    r.q_max[j] = data::kQMax[j];
  }
  return r;
}

}  // namespace dyncal::replay
