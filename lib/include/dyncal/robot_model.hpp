// The robot concept: what a generated robot type (`Robot` in
// lib/generated/<robot>/robot.hpp, included as "dyncal/generated/<robot>/robot.hpp") provides to the
// templates of lib/ (IdentificationModel, ExtendedKalmanFilter, FrictionTracker, ...), and a trait
// that checks it at compile time: static_assert(dyncal::is_robot_model<R>::value).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <type_traits>
#include <utility>

#include "dyncal/joint_capacity.hpp"

namespace dyncal {

/// A robot model type R provides (N = R::kNumJoints, n = R::kNumStandard, b = R::kNumBase; every
/// function static, constexpr or noexcept, allocation-free, templated on the scalar where it
/// computes):
///
/// - `kName` (const char*), `kRobotId` (std::uint32_t: FNV-1a of what the base parameters mean, the
///   parameter table's robot id), `kNumJoints` N in 1..kMaxRobotJoints, `kNumStandard` n = 10 N
///   (Khalil-Kleinfinger order per link: XX XY XZ YY YZ ZZ MX MY MZ M), `kNumBase` b in 1..n
///   (Gautier's base parameters);
/// - `JointVector<Scalar>` = Eigen::Matrix<Scalar, N, 1>;
/// - `standard_regressor(q, qd, qdd, Y)`: Y (N x n) with tau = Y phi; q [rad], qd [rad/s],
///   qdd [rad/s^2], tau [Nm], gravity included;
/// - `base_regressor(q, qd, qdd, Yb)`: the first b columns of Yb (N x Cols, Cols >= b), the rest
///   untouched;
/// - `inverse_dynamics(q, qd, qdd, phi, tau)` with phi the n standard parameters, and
///   `mass_matrix(q, phi, M)` (N x N);
/// - `standard_to_base(phi, phi_b)`: the b base parameters of n standard ones;
/// - names and structure: `base_param_name(i)`, `standard_param_name(i)`,
///   `base_column_first_row(b)` / `base_column_last_row(b)` (rows where base column b can be
///   nonzero), `rotor_inertia_separate(j)` / `rotor_inertia_absorbed_into(j)` (0-based joint;
///   the base parameter Ia_j is grouped into, -1 when the description declares no rotor inertia),
///   `gravity(i)` [m/s^2] along base axis i, `joint_prismatic(j)` (q [m] and tau [N] where true,
///   q [rad] and tau [Nm] where false).
template <class R, class = void>
struct is_robot_model : std::false_type {};

namespace detail {
template <class R>
using JV = Eigen::Matrix<double, R::kNumJoints, 1>;
template <class R>
using RobotModelMembers = std::void_t<
    decltype(static_cast<const char*>(R::kName)), decltype(static_cast<std::uint32_t>(R::kRobotId)),
    typename R::template JointVector<double>,
    decltype(R::standard_regressor(std::declval<const JV<R>&>(), std::declval<const JV<R>&>(),
                                   std::declval<const JV<R>&>(),
                                   std::declval<Eigen::Matrix<double, R::kNumJoints, R::kNumStandard>&>())),
    decltype(R::base_regressor(std::declval<const JV<R>&>(), std::declval<const JV<R>&>(), std::declval<const JV<R>&>(),
                               std::declval<Eigen::Matrix<double, R::kNumJoints, R::kNumBase>&>())),
    decltype(R::inverse_dynamics(
        std::declval<const JV<R>&>(), std::declval<const JV<R>&>(), std::declval<const JV<R>&>(),
        std::declval<const Eigen::Matrix<double, R::kNumStandard, 1>&>(), std::declval<JV<R>&>())),
    decltype(R::mass_matrix(std::declval<const JV<R>&>(),
                            std::declval<const Eigen::Matrix<double, R::kNumStandard, 1>&>(),
                            std::declval<Eigen::Matrix<double, R::kNumJoints, R::kNumJoints>&>())),
    decltype(R::standard_to_base(std::declval<const Eigen::Matrix<double, R::kNumStandard, 1>&>(),
                                 std::declval<Eigen::Matrix<double, R::kNumBase, 1>&>())),
    decltype(static_cast<const char*>(R::base_param_name(0))),
    decltype(static_cast<const char*>(R::standard_param_name(0))),
    decltype(static_cast<int>(R::base_column_first_row(0))), decltype(static_cast<int>(R::base_column_last_row(0))),
    decltype(static_cast<bool>(R::rotor_inertia_separate(0))),
    decltype(static_cast<int>(R::rotor_inertia_absorbed_into(0))), decltype(static_cast<double>(R::gravity(0))),
    decltype(static_cast<bool>(R::joint_prismatic(0)))>;
}  // namespace detail

template <class R>
struct is_robot_model<R, detail::RobotModelMembers<R>>
    : std::bool_constant<(R::kNumJoints >= 1 && R::kNumJoints <= kMaxRobotJoints &&
                          R::kNumStandard == 10 * R::kNumJoints && R::kNumBase >= 1 &&
                          R::kNumBase <= R::kNumStandard)> {};

template <class R>
inline constexpr bool is_robot_model_v = is_robot_model<R>::value;

}  // namespace dyncal
