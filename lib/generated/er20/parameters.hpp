// GENERATED FILE - DO NOT EDIT.
// Generator: codegen/generate.py (dyncal codegen 5, SymPy 1.11.1)
// Robot: er20; inputs: robots/er20/robot.json (sha256 4a57ae3dca2a7e3c)
// Contents: parameter index names, standard->base map, kinematic data
// Include as "dyncal/generated/er20/<file>.hpp".
// Regenerate: cmake --build <build> --target regenerate (or scripts/codegen).
#pragma once

#include <Eigen/Core>
#include <cstdint>

namespace dyncal::generated::er20 {

inline constexpr const char* kRobotName = "er20";
/// Robot id of parameter tables (dyncal/parameter_table.hpp): FNV-1a 32 of the robot name, the
/// base-parameter groupings and the joint origins, i.e. of what a base-parameter value means.
inline constexpr std::uint32_t kRobotId = 0x63a66428u;
inline constexpr int kNumJoints = 6;
/// Standard parameters: 10 per link, [XX XY XZ YY YZ ZZ] [kg m^2] about the link frame origin,
/// [MX MY MZ] [kg m], M [kg] (Khalil-Kleinfinger order).
inline constexpr int kNumStandard = 60;
/// Base parameters: independent combinations of the standard ones (Gautier 1990).
inline constexpr int kNumBase = 36;

enum class StandardParam : int {
  link1_XX = 0,
  link1_XY = 1,
  link1_XZ = 2,
  link1_YY = 3,
  link1_YZ = 4,
  link1_ZZ = 5,
  link1_MX = 6,
  link1_MY = 7,
  link1_MZ = 8,
  link1_M = 9,
  link2_XX = 10,
  link2_XY = 11,
  link2_XZ = 12,
  link2_YY = 13,
  link2_YZ = 14,
  link2_ZZ = 15,
  link2_MX = 16,
  link2_MY = 17,
  link2_MZ = 18,
  link2_M = 19,
  link3_XX = 20,
  link3_XY = 21,
  link3_XZ = 22,
  link3_YY = 23,
  link3_YZ = 24,
  link3_ZZ = 25,
  link3_MX = 26,
  link3_MY = 27,
  link3_MZ = 28,
  link3_M = 29,
  link4_XX = 30,
  link4_XY = 31,
  link4_XZ = 32,
  link4_YY = 33,
  link4_YZ = 34,
  link4_ZZ = 35,
  link4_MX = 36,
  link4_MY = 37,
  link4_MZ = 38,
  link4_M = 39,
  link5_XX = 40,
  link5_XY = 41,
  link5_XZ = 42,
  link5_YY = 43,
  link5_YZ = 44,
  link5_ZZ = 45,
  link5_MX = 46,
  link5_MY = 47,
  link5_MZ = 48,
  link5_M = 49,
  link6_XX = 50,
  link6_XY = 51,
  link6_XZ = 52,
  link6_YY = 53,
  link6_YZ = 54,
  link6_ZZ = 55,
  link6_MX = 56,
  link6_MY = 57,
  link6_MZ = 58,
  link6_M = 59
};

inline constexpr const char* kStandardParamNames[kNumStandard] = {
"link1_XX", "link1_XY", "link1_XZ", "link1_YY", "link1_YZ", "link1_ZZ", "link1_MX", "link1_MY", "link1_MZ", "link1_M", "link2_XX", "link2_XY", "link2_XZ", "link2_YY", "link2_YZ", "link2_ZZ", "link2_MX", "link2_MY", "link2_MZ", "link2_M", "link3_XX", "link3_XY", "link3_XZ", "link3_YY", "link3_YZ", "link3_ZZ", "link3_MX", "link3_MY", "link3_MZ", "link3_M", "link4_XX", "link4_XY", "link4_XZ", "link4_YY", "link4_YZ", "link4_ZZ", "link4_MX", "link4_MY", "link4_MZ", "link4_M", "link5_XX", "link5_XY", "link5_XZ", "link5_YY", "link5_YZ", "link5_ZZ", "link5_MX", "link5_MY", "link5_MZ", "link5_M", "link6_XX", "link6_XY", "link6_XZ", "link6_YY", "link6_YZ", "link6_ZZ", "link6_MX", "link6_MY", "link6_MZ", "link6_M"};

/// Base parameter names: the standard parameter each one is anchored on, with suffix _R where
/// other parameters are regrouped onto it. The groupings (numeric QR, tolerance
/// 1e-08, 200 random states):
//   link1_ZZ_R = link1_ZZ + 1*link2_YY + 0.0289*link2_M + 1*link3_YY + 0.6373*link3_M + 0.6569*link4_M + 0.6569*link5_M + 0.6569*link6_M + 1*Ia1
//   link2_XX_R = link2_XX - 1*link2_YY - 0.6084*link3_M - 0.6084*link4_M - 0.6084*link5_M - 0.6084*link6_M
//   link2_XY = link2_XY
//   link2_XZ_R = link2_XZ - 0.78*link3_MZ
//   link2_YZ = link2_YZ
//   link2_ZZ_R = link2_ZZ + 0.6084*link3_M + 0.6084*link4_M + 0.6084*link5_M + 0.6084*link6_M + 1*Ia2
//   link2_MX_R = link2_MX + 0.78*link3_M + 0.78*link4_M + 0.78*link5_M + 0.78*link6_M
//   link2_MY = link2_MY
//   link3_XX_R = link3_XX - 1*link3_YY + 1*link4_YY + 1.52*link4_MZ + 0.558*link4_M + 0.558*link5_M + 0.558*link6_M
//   link3_XY_R = link3_XY - 0.14*link4_MZ - 0.1064*link4_M - 0.1064*link5_M - 0.1064*link6_M
//   link3_XZ = link3_XZ
//   link3_YZ = link3_YZ
//   link3_ZZ_R = link3_ZZ + 1*link4_YY + 1.52*link4_MZ + 0.5972*link4_M + 0.5972*link5_M + 0.5972*link6_M
//   link3_MX_R = link3_MX + 0.14*link4_M + 0.14*link5_M + 0.14*link6_M
//   link3_MY_R = link3_MY + 1*link4_MZ + 0.76*link4_M + 0.76*link5_M + 0.76*link6_M
//   link4_XX_R = link4_XX - 1*link4_YY + 1*link5_YY
//   link4_XY = link4_XY
//   link4_XZ = link4_XZ
//   link4_YZ = link4_YZ
//   link4_ZZ_R = link4_ZZ + 1*link5_YY
//   link4_MX = link4_MX
//   link4_MY_R = link4_MY - 1*link5_MZ
//   link5_XX_R = link5_XX - 1*link5_YY + 1*link6_YY
//   link5_XY = link5_XY
//   link5_XZ = link5_XZ
//   link5_YZ = link5_YZ
//   link5_ZZ_R = link5_ZZ + 1*link6_YY
//   link5_MX = link5_MX
//   link5_MY_R = link5_MY + 1*link6_MZ
//   link6_XX_R = link6_XX - 1*link6_YY
//   link6_XY = link6_XY
//   link6_XZ = link6_XZ
//   link6_YZ = link6_YZ
//   link6_ZZ = link6_ZZ
//   link6_MX = link6_MX
//   link6_MY = link6_MY
/// Standard parameters with no effect on the torques: link1_XX, link1_XY, link1_XZ, link1_YY, link1_YZ, link1_MX, link1_MY, link1_MZ, link1_M, link2_MZ.
enum class BaseParam : int {
  link1_ZZ_R = 0,
  link2_XX_R = 1,
  link2_XY = 2,
  link2_XZ_R = 3,
  link2_YZ = 4,
  link2_ZZ_R = 5,
  link2_MX_R = 6,
  link2_MY = 7,
  link3_XX_R = 8,
  link3_XY_R = 9,
  link3_XZ = 10,
  link3_YZ = 11,
  link3_ZZ_R = 12,
  link3_MX_R = 13,
  link3_MY_R = 14,
  link4_XX_R = 15,
  link4_XY = 16,
  link4_XZ = 17,
  link4_YZ = 18,
  link4_ZZ_R = 19,
  link4_MX = 20,
  link4_MY_R = 21,
  link5_XX_R = 22,
  link5_XY = 23,
  link5_XZ = 24,
  link5_YZ = 25,
  link5_ZZ_R = 26,
  link5_MX = 27,
  link5_MY_R = 28,
  link6_XX_R = 29,
  link6_XY = 30,
  link6_XZ = 31,
  link6_YZ = 32,
  link6_ZZ = 33,
  link6_MX = 34,
  link6_MY = 35
};

inline constexpr const char* kBaseParamNames[kNumBase] = {
"link1_ZZ_R", "link2_XX_R", "link2_XY", "link2_XZ_R", "link2_YZ", "link2_ZZ_R", "link2_MX_R", "link2_MY", "link3_XX_R", "link3_XY_R", "link3_XZ", "link3_YZ", "link3_ZZ_R", "link3_MX_R", "link3_MY_R", "link4_XX_R", "link4_XY", "link4_XZ", "link4_YZ", "link4_ZZ_R", "link4_MX", "link4_MY_R", "link5_XX_R", "link5_XY", "link5_XZ", "link5_YZ", "link5_ZZ_R", "link5_MX", "link5_MY_R", "link6_XX_R", "link6_XY", "link6_XZ", "link6_YZ", "link6_ZZ", "link6_MX", "link6_MY"};

/// Standard index each base parameter is anchored on.
inline constexpr int kBaseAnchor[kNumBase] = {5, 10, 11, 12, 14, 15, 16, 17, 20, 21, 22, 24, 25, 26, 27, 30, 31, 32, 34, 35, 36, 37, 40, 41, 42, 44, 45, 46, 47, 50, 51, 52, 54, 55, 56, 57};

/// Structural sparsity of the base regressor: column b of Y_b can be nonzero only in rows
/// kBaseColumnRows[b][0]..kBaseColumnRows[b][1] (0-based joints; a link's parameters act on its
/// own joint and the joints before it). Rows outside the range are written as exact zeros.
inline constexpr int kBaseColumnRows[kNumBase][2] = {{0, 0}, {0, 1}, {0, 1}, {0, 1}, {0, 1}, {0, 1}, {0, 1}, {0, 1}, {0, 2}, {0, 2}, {0, 2}, {0, 2}, {0, 2}, {0, 2}, {0, 2}, {0, 3}, {0, 3}, {0, 3}, {0, 3}, {0, 3}, {0, 3}, {0, 3}, {0, 4}, {0, 4}, {0, 4}, {0, 4}, {0, 4}, {0, 4}, {0, 4}, {0, 5}, {0, 5}, {0, 5}, {0, 5}, {0, 5}, {0, 5}, {0, 5}};

/// Rotor inertia Ia_j (q_dd_j column, reflected to the joint side): true where it is identifiable
/// as a parameter of its own; otherwise it is absorbed into base parameter
/// kRotorInertiaAbsorbedInto[j] with coefficient kRotorInertiaAbsorbedCoefficient[j].
/// Computed only when the description declares rotor inertia (yes).
inline constexpr bool kRotorInertiaSeparate[kNumJoints] = {false, false, true, true, true, true};
inline constexpr int kRotorInertiaAbsorbedInto[kNumJoints] = {0, 5, -1, -1, -1, -1};
inline constexpr double kRotorInertiaAbsorbedCoefficient[kNumJoints] = {1.0, 1.0, 0.0, 0.0, 0.0, 0.0};

/// Joint kinds: true where joint i is prismatic (q [m] along its z axis, tau a force [N]), false
/// where it is revolute (q [rad] about z, tau [Nm]).
inline constexpr bool kJointPrismatic[kNumJoints] = {false, false, false, false, false, false};

/// Gravity [m/s^2] in the base frame.
inline constexpr double kGravity[3] = {0.0, 0.0, -9.81};

/// Joint i's fixed transform before its motion along z: rotation (row-major) and offset [m]
/// in the parent frame, T(i-1, i) = [R p] * Rz(q_i), or [R p] * Tz(q_i) where kJointPrismatic[i].
struct JointOrigin {
  double R[9];
  double p[3];
};
inline constexpr JointOrigin kJointOrigins[kNumJoints] = {
    {{1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0}, {0.0, 0.0, 0.504}},
    {{0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0}, {0.17, 0.0, 0.0}},
    {{1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0}, {0.78, 0.0, 0.0}},
    {{1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 0.0}, {0.14, 0.76, 0.0}},
    {{1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0}, {0.0, 0.0, 0.0}},
    {{1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 0.0}, {0.0, 0.0, 0.0}}};

/// Nominal standard parameters from the description (CAD / URDF values), StandardParam order.
inline constexpr double kNominalStandard[kNumStandard] = {1.824, 0.08, 0.25000000000000006, 1.85, -0.11, 1.074, 3.0, -1.2, -6.0, 60.0, 1.1759999999999997, 0.0, 1.9720000000000002, 9.46, 0.0, 8.684000000000001, 15.600000000000001, 0.0, -4.8, 40.0, 1.007372969555, -0.482004696082, -0.06559961405600004, 0.9215789234199998, -0.544245486396, 0.9514202282389999, 2.4020585399999996, 3.54162789, 2.98080612, 25.6083, 1.5312, 0.0, 0.0, 1.53, -0.026000000000000002, 0.05120000000000004, 0.0, -0.12, -3.5999999999999996, 12.0, 0.0216, 0.0, 0.0, 0.015, 0.0, 0.0216, 0.0, 0.08, 0.0, 4.0, 0.0104, 0.0, 0.0, 0.0104, 0.0, 0.002, 0.0, 0.0, 0.08, 1.0};

/// Standard -> base parameters: phi_b (36) from phi (60). Rotor inertia is not included.
template <typename Scalar>
inline void standard_to_base(const Eigen::Matrix<Scalar, 60, 1>& phi, Eigen::Matrix<Scalar, 36, 1>& phi_b) noexcept {
  phi_b[0] = phi[5] + Scalar(1.0) * phi[13] + Scalar(0.0289) * phi[19] + Scalar(1.0) * phi[23] + Scalar(0.6373) * phi[29] + Scalar(0.6569) * phi[39] + Scalar(0.6569) * phi[49] + Scalar(0.6569) * phi[59];
  phi_b[1] = phi[10] + Scalar(-1.0) * phi[13] + Scalar(-0.6084) * phi[29] + Scalar(-0.6084) * phi[39] + Scalar(-0.6084) * phi[49] + Scalar(-0.6084) * phi[59];
  phi_b[2] = phi[11];
  phi_b[3] = phi[12] + Scalar(-0.78) * phi[28];
  phi_b[4] = phi[14];
  phi_b[5] = phi[15] + Scalar(0.6084) * phi[29] + Scalar(0.6084) * phi[39] + Scalar(0.6084) * phi[49] + Scalar(0.6084) * phi[59];
  phi_b[6] = phi[16] + Scalar(0.78) * phi[29] + Scalar(0.78) * phi[39] + Scalar(0.78) * phi[49] + Scalar(0.78) * phi[59];
  phi_b[7] = phi[17];
  phi_b[8] = phi[20] + Scalar(-1.0) * phi[23] + Scalar(1.0) * phi[33] + Scalar(1.52) * phi[38] + Scalar(0.558) * phi[39] + Scalar(0.558) * phi[49] + Scalar(0.558) * phi[59];
  phi_b[9] = phi[21] + Scalar(-0.14) * phi[38] + Scalar(-0.1064) * phi[39] + Scalar(-0.1064) * phi[49] + Scalar(-0.1064) * phi[59];
  phi_b[10] = phi[22];
  phi_b[11] = phi[24];
  phi_b[12] = phi[25] + Scalar(1.0) * phi[33] + Scalar(1.52) * phi[38] + Scalar(0.5972) * phi[39] + Scalar(0.5972) * phi[49] + Scalar(0.5972) * phi[59];
  phi_b[13] = phi[26] + Scalar(0.14) * phi[39] + Scalar(0.14) * phi[49] + Scalar(0.14) * phi[59];
  phi_b[14] = phi[27] + Scalar(1.0) * phi[38] + Scalar(0.76) * phi[39] + Scalar(0.76) * phi[49] + Scalar(0.76) * phi[59];
  phi_b[15] = phi[30] + Scalar(-1.0) * phi[33] + Scalar(1.0) * phi[43];
  phi_b[16] = phi[31];
  phi_b[17] = phi[32];
  phi_b[18] = phi[34];
  phi_b[19] = phi[35] + Scalar(1.0) * phi[43];
  phi_b[20] = phi[36];
  phi_b[21] = phi[37] + Scalar(-1.0) * phi[48];
  phi_b[22] = phi[40] + Scalar(-1.0) * phi[43] + Scalar(1.0) * phi[53];
  phi_b[23] = phi[41];
  phi_b[24] = phi[42];
  phi_b[25] = phi[44];
  phi_b[26] = phi[45] + Scalar(1.0) * phi[53];
  phi_b[27] = phi[46];
  phi_b[28] = phi[47] + Scalar(1.0) * phi[58];
  phi_b[29] = phi[50] + Scalar(-1.0) * phi[53];
  phi_b[30] = phi[51];
  phi_b[31] = phi[52];
  phi_b[32] = phi[54];
  phi_b[33] = phi[55];
  phi_b[34] = phi[56];
  phi_b[35] = phi[57];
}

}  // namespace dyncal::generated::er20
