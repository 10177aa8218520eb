// GENERATED FILE - DO NOT EDIT.
// Generator: host_sim/tools/replay_data.cpp --ratings (cmake --build <build> --target replay-data)
// Input: robots/er20/robot.json (limits, joint side), robots/er20/drive.json (the simulated arm).
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

/// The arm the drive image simulates (port/cortex_m/app/simulated_arm.hpp): the host simulated
/// drive's default scenario of the er20 (robots/er20/robot.json, drive.json). Eq. 7 friction Fc [Nm],
/// beta [Nm s/rad]; reflected rotor inertia J_m N^2 [kg m^2]; torque measurement noise std [Nm];
/// encoder quantum on the joint side 2 pi / (counts N) [rad].
inline constexpr double kCoulomb[6] = {60.000000000000000, 55.000000000000000, 50.000000000000000, 12.000000000000000, 10.000000000000000, 8.0000000000000000};
inline constexpr double kViscous[6] = {45.000000000000000, 42.000000000000000, 40.000000000000000, 8.0000000000000000, 7.0000000000000000, 5.0000000000000000};
inline constexpr double kRotorInertia[6] = {6.7500000000000000, 6.7500000000000000, 2.1599999999999997, 0.19200000000000000, 0.19200000000000000, 0.074999999999999997};
inline constexpr double kTauNoiseStd[6] = {10.000000000000000, 10.000000000000000, 10.000000000000000, 1.7800000000000000, 1.7800000000000000, 1.7800000000000000};
inline constexpr double kQuantum[6] = {3.1957933080950855e-07, 3.1957933080950855e-07, 3.9947416351188570e-07, 5.9921124526782858e-07, 5.9921124526782858e-07, 9.5873799242852582e-07};
/// The control loop: rate [Hz], RK4 substeps per period, PD natural frequency [Hz] and damping.
inline constexpr double kControlRateHz = 1000.0000000000000;
inline constexpr int kSubsteps = 2;
inline constexpr double kBandwidthHz = 8.0000000000000000;
inline constexpr double kDamping = 1.0000000000000000;

}  // namespace dyncal::replay::data
// clang-format on
