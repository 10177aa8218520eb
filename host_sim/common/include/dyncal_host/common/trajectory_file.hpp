#pragma once
// An excitation trajectory's file (JSON: {robot, f_f, harmonics, q0, a, b}) and the share of each
// joint's limits it uses: what `dyncal excite` writes and every command that plays one reads
// (calibrate --trajectory, identify --law, the survey).

#include <array>
#include <nlohmann/json.hpp>

#include "dyncal/modbus_map.hpp"
#include "dyncal_host/common/excitation_trajectory.hpp"
#include "dyncal_host/common/robot_description.hpp"

namespace dyncal::host {

/// Per joint (joint 1 first; entries past the robot's joints are 0): a fraction of a limit.
using JointFractions = std::array<double, modbus_map::kMaxJoints>;

/// Extremes of q, qd, qdd over one period of `t` on `grid` points (rows past the joints unused).
using TrajectoryVec = Eigen::Matrix<double, modbus_map::kMaxJoints, 1>;
void trajectory_extremes(const ExcitationTrajectory& t, int grid, TrajectoryVec& qmin, TrajectoryVec& qmax,
                         TrajectoryVec& vmax, TrajectoryVec& amax);

/// Fraction of each joint's limits `t` uses, checked on a grid 10 times finer than the design's.
void limit_use(const RobotDescription& robot, const ExcitationTrajectory& t, JointFractions& position,
               JointFractions& velocity, JointFractions& acceleration);

/// {"f_f", "harmonics", "q0" [N], "a" [N][L], "b" [N][L], "robot"} plus `extra` fields.
nlohmann::json trajectory_to_json(const RobotDescription& robot, const ExcitationTrajectory& t);
/// Reads a trajectory file; throws InputError naming the problem (missing field, wrong size, other
/// robot, or a limit exceeded: the joint, the quantity and by how much).
ExcitationTrajectory trajectory_from_json(const RobotDescription& robot, const nlohmann::json& j);

}  // namespace dyncal::host
