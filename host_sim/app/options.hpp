#pragma once
// What the subcommands share (options.cpp): their robot and log options, the drive they connect to,
// their output files checked before the work and written all or nothing.

#include <CLI/CLI.hpp>
#include <initializer_list>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "dyncal_host/common/json_file.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/logs/joint_log.hpp"
#include "dyncal_port/modbus_drive.hpp"

namespace dyncal::app {

using host::read_json_file;  ///< json_file.hpp: one-line errors naming the file
/// Writes `j` (indented) to `path` through write_output_file (output_file.hpp: all or nothing, a
/// regular file or a new name only; `what` names it in the error). Throws InputError, one line.
void write_json_file(const std::string& path, const nlohmann::json& j, const char* what = "output file");

/// Checks each non-empty output path as write_output_file will write it (a regular file or a new name
/// in an existing folder; output_file.hpp), before a command's work: a FIFO, a device, a folder or a
/// missing folder is refused at once, not after the fit. Each entry: the path and what it is.
void check_outputs(std::initializer_list<std::pair<const std::string&, const char*>> outputs);

/// The drive at `uri` (tcp://HOST:PORT or rtu:DEVICE). Throws InputError when it cannot be reached.
std::unique_ptr<linux_port::ModbusDrive> connect_drive(const std::string& uri);

/// The robot a command works on: --robot NAME under --robots-dir.
struct RobotOption {
  std::string name;
  std::string robots_dir;
  /// Without --robot, load() takes the robots directory's default (default_robot_name) instead of
  /// refusing.
  bool default_robot = false;
  /// Adds --robot (with `help`) and --robots-dir to `cmd`.
  void add_to(CLI::App* cmd, const std::string& help);
  /// The robot's description. Throws InputError (unknown robot, malformed robot.json).
  host::RobotDescription load() const;
};

/// A measured log: --format csv|ur-rtde|tx40, --columns, --data, and the robot (by default with a
/// vendor format, the robot whose robot.json lists it in log_formats).
struct LogOption {
  RobotOption robot;
  std::string format = "csv";
  std::string torque_from = "torque";  ///< csv logs: "torque" (tau1..tauN [Nm]) or "current" (i1..iN [A])
  std::string columns;                 ///< csv logs: a logger's named columns (column_map.hpp), empty: dyncal's
  std::vector<std::string> data;       ///< one or more logs (--data A --data B): stacked as segments
  bool drop_outliers = false;
  bool merge_on_time = false;    ///< csv: the --data files are one log split by signal (merged_files.hpp)
  std::string topic;             ///< ROS 2 bags: the JointState topic; empty: the bag's only one
  std::string effort;            ///< ROS 2 bags: what JointState.effort holds, "torque" or "current" (required)
  std::string clock = "header";  ///< ROS 2 bags: "header" (the message's stamp) or "log" (the recorder's time)
  /// Adds --format, --torque-from, --columns, --data, --drop-outliers, the bag options (--topic, --effort,
  /// --clock) and the robot options to `cmd`; returns
  /// --data's option (required unless `data_required` is false: the command checks it then).
  CLI::Option* add_to(CLI::App* cmd, bool data_required = true);
  /// The robot: --robot, or the one robot listing --format in its robot.json's log_formats
  /// (robot_for_log_format). Throws InputError (no --robot and no such robot, ...).
  host::RobotDescription load_robot() const;
  /// The log on the joint side (TX40 files through the robot's transmission), checked for physical
  /// plausibility against the robot's limits (log_plausibility.hpp); several --data logs stacked as
  /// segments (uniform_grid.hpp: stack_logs), or with --merge-on-time merged into one log by signal
  /// (merged_files.hpp, its note into *dropped). Throws InputError (unreadable, malformed, an
  /// implausible value without --drop-outliers). With --drop-outliers, *dropped (if given) receives
  /// one line per replaced value.
  host::JointLog load_log(const host::RobotDescription& robot, std::vector<std::string>* dropped = nullptr) const;
  /// As load_log, for the logs at `paths` (in --format) instead of --data.
  host::JointLog load_logs(const host::RobotDescription& robot, const std::vector<std::string>& paths,
                           std::vector<std::string>* dropped = nullptr) const;
  /// The ROS 2 bag at `path` (ros2_bag.hpp) as a joint-side log: --effort declared (current: through
  /// the robot's torque constants), joints matched by robot.json's names; the reading's notes (topic,
  /// clocks, joints ignored) appended to *notes. Throws InputError (no --effort, a robot without joint
  /// names, the bag's errors).
  host::JointLog load_bag(const host::RobotDescription& robot, const std::string& path,
                          std::vector<std::string>* notes) const;
};

}  // namespace dyncal::app
