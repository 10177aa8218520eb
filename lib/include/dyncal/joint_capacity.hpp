#pragma once
// The one joint capacity every part sizes its joint arrays by: the robot models, the port's
// samples, the register map and the simulated drive.

namespace dyncal {

/// Joints an arm may have: serial chains of 1 to 7 joints, revolute or prismatic.
inline constexpr int kMaxRobotJoints = 7;

}  // namespace dyncal
