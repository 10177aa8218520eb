#pragma once
// A logger's named columns as dyncal's signals (docs/cli.md "Logs"): which column holds the time,
// each joint's position, velocity, acceleration and effort, and in what units.

#include <string>
#include <vector>

#include "dyncal_host/logs/joint_log.hpp"

namespace dyncal::host {

/// Per signal, the logger's column names (joint 1 first) and the factors that take its values to
/// dyncal's units: t [s]; on a revolute joint q [rad], qd [rad/s], qdd [rad/s^2], effort [Nm]
/// (*_scale), on a prismatic one q [m], qd [m/s], qdd [m/s^2], effort [N] (*_linear_scale,
/// force_scale); or, with effort_is_current, motor current [A] (converted by the robot's torque
/// constants afterwards: current_to_joint_torque). qd and qdd empty: not in the log (computed).
struct ColumnMap {
  std::string t;
  std::vector<std::string> q, qd, qdd, effort;
  double t_scale = 1, q_scale = 1, qd_scale = 1, qdd_scale = 1, effort_scale = 1;
  double q_linear_scale = 1, qd_linear_scale = 1, qdd_linear_scale = 1, force_scale = 1;
  bool effort_is_current = false;
  std::vector<bool> prismatic;  ///< per joint (RobotDescription::prismatic); empty: all revolute
  std::string origin;           ///< what the map came from, for messages ("--columns", "--format ur-rtde")
  /// The factor of joint j (0-based): `scale` on a revolute joint, `linear_scale` on a prismatic one.
  double joint_scale(int j, double scale, double linear_scale) const {
    const bool linear = static_cast<size_t>(j) < prismatic.size() && prismatic[static_cast<size_t>(j)];
    return linear ? linear_scale : scale;
  }
};

/// Parses `--columns`: entries `signal=names[:unit]` separated by commas, signal one of t, q, qd,
/// qdd, tau. names is one column name, or a pattern with one range {a..b} (a <= b, integers) that
/// expands to one name per joint: `q=actual_q_{0..5}` is actual_q_0 .. actual_q_5. Units: t s (the
/// default), ms, us, ns; q rad, deg | m, mm; qd rad/s, deg/s | m/s, mm/s; qdd rad/s^2, deg/s^2 |
/// m/s^2, mm/s^2; tau Nm, mNm | N, or current (motor current [A]). An angular unit applies to the
/// revolute joints, a linear one to the prismatic joints (`prismatic`: per joint, the robot's
/// RobotDescription::prismatic; its length is the number of joints). A signal without a unit is read
/// in SI on every joint; one with units needs a unit for each joint kind the robot has, as
/// `deg|mm` on a mixed arm. t, q and tau are required. Throws InputError naming the entry: an
/// unknown signal or unit, a repeated signal, a range that does not give one name per joint, a
/// malformed range, a unit of a kind the robot has no joint of, a mixed arm given one kind's unit.
ColumnMap parse_column_map(const std::string& spec, const std::vector<bool>& prismatic);

/// The built-in map of Universal Robots' RTDE recorder (its CSV: `timestamp`, `actual_q_0..`,
/// `actual_qd_0..`, `actual_current_0..`; space-separated by default): time [s], measured joint
/// positions [rad] and velocities [rad/s], and the motors' measured currents [A] as the effort (the
/// recorder's `target_moment_*` is a command, not a measurement).
ColumnMap ur_rtde_column_map(const std::vector<bool>& prismatic);

/// Reads a delimited log (read_numeric_csv: comma, semicolon, tab or space separated) with the
/// columns `map` names; other columns are ignored. The effort lands in `tau` as it is (currents
/// when map.effort_is_current: convert with current_to_joint_torque). Throws InputError naming the
/// file and the first column the log lacks, or as read_numeric_csv and read_csv_log (time not
/// strictly increasing, fewer than 3 samples).
JointLog read_mapped_csv_log(const std::string& path, const ColumnMap& map, int joints);

}  // namespace dyncal::host
