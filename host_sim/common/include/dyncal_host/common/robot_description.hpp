#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace dyncal::host {

/// A joint's nominal friction from robot.json's "friction" list (survey Eq. 4 parameters; zeros
/// where the file has none): Coulomb Fc [Nm], viscous beta [Nm s/rad], static Fs [Nm], Stribeck
/// velocity qds [rad/s].
struct NominalFriction {
  double Fc = 0, beta = 0, Fs = 0, qds = 0.1;
};

/// Drive and limit data of a robot, from robots/<name>/robot.json (kinematics and inertials go to
/// the code generator instead). Vectors are per joint, joint 1 first; SI units.
struct RobotDescription {
  std::string name;
  std::string directory;
  int num_joints = 0;
  Eigen::VectorXd gear_ratios;    ///< motor turns per joint turn (signed)
  Eigen::MatrixXd transmission;   ///< N: q_motor = N q_joint, tau_joint = N^T tau_motor
  Eigen::VectorXd joint_offsets;  ///< added to N^-1 q_motor to give the model's q [rad]
  Eigen::VectorXd q_min, q_max, qd_max, qdd_max;
  Eigen::VectorXd tau_max;                ///< maximum joint driving torque [Nm] (survey Sec. 5.1)
  std::vector<NominalFriction> friction;  ///< per joint (num_joints entries); Fs defaults to Fc
};

/// Loads robots/<name>/robot.json below `robots_dir`. Throws InputError naming the problem
/// (unknown robot, missing field, wrong vector length).
RobotDescription load_robot(const std::string& robots_dir, const std::string& name);

/// The robots directory: $DYNCAL_ROBOTS if set, else the source tree's robots/ (compiled in).
std::string default_robots_dir();

}  // namespace dyncal::host
