// Options and files several subcommands share.
#include "options.hpp"

#include <fstream>
#include <optional>
#include <utility>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/output_file.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/logs/column_map.hpp"
#include "dyncal_host/logs/log_plausibility.hpp"
#include "dyncal_host/logs/merged_files.hpp"
#include "dyncal_host/logs/ros2_bag.hpp"
#include "dyncal_host/logs/uniform_grid.hpp"
#include "dyncal_host/model/compiled_robot.hpp"

namespace dyncal::app {

using host::InputError;

void write_json_file(const std::string& path, const nlohmann::json& j, const char* what) {
  host::write_output_file(path, j.dump(2) + "\n", what);
}

void check_outputs(std::initializer_list<std::pair<const std::string&, const char*>> outputs) {
  for (const auto& [path, what] : outputs)
    if (!path.empty()) host::check_output_path(path, what);
}

std::unique_ptr<linux_port::ModbusDrive> connect_drive(const std::string& uri) {
  std::string error;
  auto d = linux_port::ModbusDrive::connect(uri, &error);
  if (!d) throw InputError(error);
  return d;
}

void RobotOption::add_to(CLI::App* cmd, const std::string& help) {
  robots_dir = host::default_robots_dir();
  cmd->add_option("--robot", name, help);
  cmd->add_option("--robots-dir", robots_dir, "directory holding the robot descriptions");
}

host::RobotDescription RobotOption::load() const {
  if (name.empty() && !default_robot) throw InputError("--robot is required (robots/<name>/; docs/robots.md)");
  return host::load_checked_robot(robots_dir, name.empty() ? host::default_robot_name(robots_dir) : name);
}

CLI::Option* LogOption::add_to(CLI::App* cmd, bool data_required) {
  robot.add_to(cmd,
               "robot name (robots/<name>/); by default with a vendor --format, the robot whose robot.json lists it in "
               "log_formats");
  cmd->add_option("--format", format,
                  "log format: csv (t,q1..qN,[qd..],[qdd..],tau1..tauN, or --columns; a ROS 2 bag given to --data "
                  "is read as one), ur-rtde (Universal Robots' RTDE recorder: timestamp, actual_q_*, actual_qd_*, "
                  "actual_current_* as motor current), tx40, or ros2-bag (an .mcap, a .db3, or a rosbag2 folder)")
      ->check(CLI::IsMember({"csv", "ur-rtde", "tx40", "ros2-bag"}));
  cmd->add_option("--topic", topic, "ROS 2 bags: the sensor_msgs/msg/JointState topic (default: the bag's only one)");
  cmd->add_option("--effort", effort,
                  "ROS 2 bags: what JointState.effort holds, as the robot's driver publishes it: torque (joint torque "
                  "[Nm]) or current (motor current [A], tau = N^T diag(Kt) i); required, never guessed")
      ->check(CLI::IsMember({"torque", "current"}));
  cmd->add_option("--clock", clock,
                  "ROS 2 bags: the samples' time, header (the message's stamp, when the driver sampled) or log (when "
                  "the recorder received it); both are reported")
      ->check(CLI::IsMember({"header", "log"}));
  cmd->add_option("--torque-from", torque_from,
                  "csv logs: torque (columns tau1..tauN, joint torque [Nm]) or current (columns i1..iN, motor "
                  "current [A]; tau = N^T diag(Kt) i with robot.json's transmission.torque_constants and gear "
                  "ratios)")
      ->check(CLI::IsMember({"torque", "current"}));
  cmd->add_option(
      "--columns", columns,
      "csv logs with a logger's column names: signal=column[:unit] entries, comma-separated, a {a..b} "
      "range per joint, e.g. 't=time:ms,q=pos_{1..6}:deg,qd=vel_{1..6}:deg/s,tau=cur_{1..6}:current' "
      "(units: t s, ms, us, ns; q rad, deg, m, mm; qd rad/s, deg/s, m/s, mm/s; qdd rad/s^2, deg/s^2, m/s^2, "
      "mm/s^2; tau Nm, mNm, N, current; an angular unit is the revolute joints', a linear one the "
      "prismatic joints', one of each on an arm with both: q=pos{1..4}:deg|mm; SI where none is given)");
  CLI::Option* data_option =
      cmd->add_option("--data", data,
                      "CSV log file (time-stamped; jitter and missing samples allowed), or the folder of the TX40 "
                      "files; repeat to stack several logs as segments");
  if (data_required) data_option->required();
  cmd->add_flag("--merge-on-time", merge_on_time,
                "csv: the --data files are one log split by signal (e.g. positions, velocities and efforts logged "
                "apart, each file with its own time column: the map's t, else its first column), merged on the "
                "positions' stamps by linear interpolation (docs/cli.md \"Logs\")");
  cmd->add_flag("--drop-outliers", drop_outliers,
                "replace physically implausible values (beyond the robot's limits by a wide margin, docs/cli.md) by "
                "interpolation and report each, instead of refusing the log");
  return data_option;
}

host::RobotDescription LogOption::load_robot() const {
  RobotOption r = robot;
  if (r.name.empty()) r.name = host::robot_for_log_format(r.robots_dir, format);
  return r.load();
}

host::JointLog LogOption::load_log(const host::RobotDescription& r, std::vector<std::string>* dropped) const {
  return load_logs(r, data, dropped);
}

host::JointLog LogOption::load_bag(const host::RobotDescription& r, const std::string& path,
                                   std::vector<std::string>* notes) const {
  if (!columns.empty()) throw InputError("--columns maps a CSV's columns; " + path + " is a ROS 2 bag");
  if (torque_from == "current")
    throw InputError("--torque-from is for CSV logs; a ROS 2 bag's JointState.effort is declared with --effort");
  if (effort.empty())
    throw InputError(path +
                     ": a ROS 2 bag's JointState.effort is joint torque or motor current depending on the "
                     "robot's driver; declare which with --effort torque|current");
  if (r.joint_names.empty())
    throw InputError(r.directory +
                     "/robot.json names no joints (joint_names, or source.joints of robot import); a "
                     "bag's JointState is matched to the robot by joint name (docs/robots.md)");
  if (effort == "current" && r.torque_constants.size() == 0)
    throw InputError("--effort current: " + r.directory +
                     "/robot.json has no transmission.torque_constants (Nm/A per motor; docs/robots.md)");
  host::BagLogOptions options;
  options.topic = topic;
  options.clock = clock == "log" ? host::BagClock::log : host::BagClock::header;
  options.joint_names = r.joint_names;
  host::BagLog bag = host::read_ros2_bag_log(path, options);
  if (effort == "current") host::current_to_joint_torque(bag.log, r.transmission, r.torque_constants, path);
  if (notes) notes->insert(notes->end(), bag.notes.begin(), bag.notes.end());
  return std::move(bag.log);
}

host::JointLog LogOption::load_logs(const host::RobotDescription& r, const std::vector<std::string>& paths,
                                    std::vector<std::string>* dropped) const {
  if (torque_from == "current" && format == "tx40")
    throw InputError("--torque-from current: the TX40 format holds motor torques already");
  // A logger's named columns: --columns, or the preset of --format ur-rtde.
  std::optional<host::ColumnMap> map;
  if (!columns.empty() && format != "csv")
    throw InputError("--columns maps a CSV's columns; --format " + format + " has its own");
  if (!columns.empty()) map = host::parse_column_map(columns, r.prismatic);
  if (format == "ur-rtde") map = host::ur_rtde_column_map(r.prismatic);
  if (map && torque_from == "current") map->effort_is_current = true;
  // Motor currents need the torque constants: refused before any file is read.
  if ((torque_from == "current" || (map && map->effort_is_current)) && r.torque_constants.size() == 0)
    throw InputError(
        (torque_from == "current" ? std::string("--torque-from current") : map->origin + " reads motor currents") +
        ": " + r.directory + "/robot.json has no transmission.torque_constants (Nm/A per motor; docs/robots.md)");
  if (merge_on_time) {
    if (format != "csv") throw InputError("--merge-on-time merges CSV files; --format " + format + " is not csv");
    for (const std::string& path : paths)
      if (host::is_ros2_bag(path)) throw InputError("--merge-on-time merges CSV files; " + path + " is a ROS 2 bag");
    host::ColumnMap m = map ? *map : host::default_column_map(r.prismatic, torque_from == "current");
    std::vector<std::string> notes;
    host::JointLog log = host::read_merged_csv_logs(paths, m, r.num_joints, &notes);
    if (m.effort_is_current) host::current_to_joint_torque(log, r.transmission, r.torque_constants, log.source);
    const auto lines = host::check_plausibility(log, r, drop_outliers);
    if (dropped) {
      dropped->insert(dropped->end(), notes.begin(), notes.end());
      dropped->insert(dropped->end(), lines.begin(), lines.end());
    }
    return log;
  }
  std::vector<host::JointLog> logs;
  for (const std::string& path : paths) {
    host::JointLog log;
    if (format == "ros2-bag" || (format == "csv" && !map && host::is_ros2_bag(path))) {
      log = load_bag(r, path, dropped);
    } else if (!topic.empty() || !effort.empty()) {
      throw InputError("--topic and --effort are for ROS 2 bags; " + path + " is not one");
    } else if (map) {
      log = host::read_mapped_csv_log(path, *map, r.num_joints);
      if (map->effort_is_current) host::current_to_joint_torque(log, r.transmission, r.torque_constants, path);
    } else {
      log = format == "tx40"           ? host::read_tx40_log(path, r.transmission, r.joint_offsets)
            : torque_from == "current" ? host::read_current_csv_log(path, r.transmission, r.torque_constants)
                                       : host::read_csv_log(path, r.num_joints);
    }
    const auto lines = host::check_plausibility(log, r, drop_outliers);
    if (dropped) dropped->insert(dropped->end(), lines.begin(), lines.end());
    logs.push_back(std::move(log));
  }
  return host::stack_logs(std::move(logs));
}

}  // namespace dyncal::app
