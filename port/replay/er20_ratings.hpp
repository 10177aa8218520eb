// GENERATED FILE - DO NOT EDIT.
// Generator: host_sim/tools/replay_data.cpp --ratings (cmake --build <build> --target replay-data)
// Input: robots/er20/robot.json (limits, joint side).
#pragma once

// clang-format off
namespace dyncal::replay::data {

/// The er20's ratings: tau_max [Nm], qd_max [rad/s], qdd_max [rad/s^2], q_min, q_max [rad]; the
/// parameter store's table plausibility (dyncal/table_check.hpp JointRatings).
inline constexpr float kTauMax[6] = {1200.00000f, 1300.00000f, 600.000000f, 110.000000f, 110.000000f, 60.0000000f};
inline constexpr float kQdMax[6] = {2.97000003f, 2.97000003f, 3.31999993f, 6.11000013f, 6.11000013f, 9.42000008f};
inline constexpr float kQddMax[6] = {10.0000000f, 10.0000000f, 12.0000000f, 20.0000000f, 20.0000000f, 30.0000000f};
inline constexpr float kQMin[6] = {-2.96000004f, -1.57000005f, -1.04999995f, -3.14000010f, -2.18000007f, -6.28000021f};
inline constexpr float kQMax[6] = {2.96000004f, 2.61999989f, 2.78999996f, 3.14000010f, 2.18000007f, 6.28000021f};

}  // namespace dyncal::replay::data
// clang-format on
