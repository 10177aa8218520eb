#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "dyncal/joint_capacity.hpp"

namespace dyncal::host {

/// A joint's nominal friction from robot.json's "friction" list (survey Eq. 4 parameters; zeros
/// where the file has none): Coulomb Fc [Nm], viscous beta [Nm s/rad], static Fs [Nm], Stribeck
/// velocity qds [rad/s].
struct NominalFriction {
  double Fc = 0, beta = 0, Fs = 0, qds = 0.1;
};

/// A link's inertial as an MDH robot.json states it ("links"; docs/robots.md): mass [kg], centre of
/// mass [m] in the link frame, inertia [kg m^2] about the centre of mass (ixx ixy ixz iyy iyz izz).
struct LinkInertialSpec {
  double mass = 0;
  std::array<double, 3> com{};
  std::array<double, 6> inertia{};
};

/// Joints a robot may have (lib/'s joint capacity).
inline constexpr int kMaxRobotDescriptionJoints = kMaxRobotJoints;
/// qdd_max when robot.json gives none: kDefaultQddPerQd * qd_max [rad/s^2], top speed in 0.25 s.
inline constexpr double kDefaultQddPerQd = 4.0;

/// Drive and limit data of a robot, from robots/<name>/robot.json (kinematics and inertials go to
/// the code generator instead; docs/robots.md is the schema). Vectors are per joint, joint 1 first;
/// SI units, joint side.
struct RobotDescription {
  std::string name;
  std::string directory;
  std::string kinematics_format;  ///< kinematics.format: "mdh" or "urdf"
  /// An MDH robot's links (one per joint), checked against its compiled model (compiled_robot_for);
  /// empty for a URDF robot, whose inertials are in its URDF (robot check compares it with KDL).
  std::vector<LinkInertialSpec> links;
  /// Vendor log formats (`--format`) this arm's controller writes: "--format F" without --robot
  /// takes the robot listing F (robot_for_log_format). Empty when the file lists none.
  std::vector<std::string> log_formats;
  int num_joints = 0;  ///< the length of limits.q_min, 1..kMaxRobotDescriptionJoints
  /// Per joint: true where it is prismatic (q [m], qd [m/s], tau a force [N]), false where it is
  /// revolute (q [rad], tau [Nm]): robot.json's "joint_types" (a URDF robot; all revolute when
  /// absent) or the MDH rows' "sigma" (1: prismatic; Khalil-Kleinfinger).
  std::vector<bool> prismatic;
  Eigen::VectorXd gear_ratios;    ///< motor turns per joint turn (signed); 1 without "transmission"
  Eigen::MatrixXd transmission;   ///< N: q_motor = N q_joint, tau_joint = N^T tau_motor
  Eigen::VectorXd joint_offsets;  ///< added to N^-1 q_motor to give the model's q [rad]; default 0
  /// Motor torque per ampere of motor current [Nm/A], per motor (signed: a negative constant is a
  /// drive whose current sign is opposite to its motor torque); empty when the file gives none.
  /// Used by logs of motor current: tau_joint = N^T diag(torque_constants) i_motor.
  Eigen::VectorXd torque_constants;
  Eigen::VectorXd q_min, q_max, qd_max;
  Eigen::VectorXd qdd_max;  ///< [rad/s^2]; kDefaultQddPerQd * qd_max when the file gives none
  /// Maximum joint driving torque [Nm] (survey Sec. 5.1). Empty when the file gives none: then
  /// derive_tau_max (compiled_robot.hpp) fills it from the nominal model and sets tau_max_derived.
  Eigen::VectorXd tau_max;
  bool tau_max_derived = false;
  std::vector<NominalFriction> friction;  ///< per joint (num_joints entries); Fs defaults to Fc
  /// The joints' names as the robot's own software publishes them (a ROS 2 bag's JointState is
  /// matched by them): robot.json's "joint_names", else "source.joints" (the URDF joints `robot
  /// import` kept); empty when the file gives neither.
  std::vector<std::string> joint_names;
};

/// Whether joint j (0-based) is prismatic (false for a joint the description does not list).
bool is_prismatic(const RobotDescription& robot, int j);
/// Unit of joint j's (0-based) effort: "N" where it is prismatic, else "Nm".
const char* effort_unit(const RobotDescription& robot, int j);

/// Loads robots/<name>/robot.json below `robots_dir`. Throws InputError on one line naming the file
/// and the field as docs/robots.md does (unknown robot, not a file, invalid JSON, a field missing,
/// of the wrong type or length, non-finite, q_max <= q_min, a zero gear ratio or torque constant, a
/// coupling out of range,
/// more than 7 joints).
RobotDescription load_robot(const std::string& robots_dir, const std::string& name);

/// The robots directory: $DYNCAL_ROBOTS if set, else the source tree's robots/ (compiled in).
std::string default_robots_dir();

/// The robot a command takes when given no --robot: the name in `robots_dir`/default.txt (its first
/// line that is neither empty nor a # comment). Throws InputError when the file is missing or names
/// no folder of `robots_dir`.
std::string default_robot_name(const std::string& robots_dir);

/// The one robot under `robots_dir` whose robot.json lists `format` in "log_formats": a vendor's log
/// format that itself says which arm recorded it. Folders whose robot.json does not
/// parse are passed over (loading them reports it). Throws InputError when no robot or several list
/// it.
std::string robot_for_log_format(const std::string& robots_dir, const std::string& format);

}  // namespace dyncal::host
