#pragma once
// The dyncal subcommands, one file each. Each add_*_command adds its subcommand to the app; when the
// user chooses it, its parse callback sets `run` to the action, which main() then calls. Actions
// throw InputError on bad input (main prints it on one line, exit 2) and return the exit code.

#include <CLI/CLI.hpp>
#include <functional>
#include <initializer_list>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "dyncal_host/common/json_file.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/identification/logs/joint_log.hpp"
#include "dyncal_port/modbus_drive.hpp"

namespace dyncal::app {

using Action = std::function<int()>;

void add_identify_command(CLI::App& app, Action& run);
void add_diagnose_command(CLI::App& app, Action& run);
void add_excite_command(CLI::App& app, Action& run);
/// The survey study itself, run in-process: the `survey` subcommand of the program dyncal-survey.
void add_survey_command(CLI::App& app, Action& run);
/// dyncal's `survey`: hands its arguments to the program dyncal-survey beside the running program
/// (execv; the study and its er20-typed methods are compiled into that program alone, so that
/// building `dyncal` does not compile them). Throws InputError (one line) when that program is not
/// there or cannot be run.
void add_survey_launcher(CLI::App& app, Action& run);
void add_drive_command(CLI::App& app, Action& run);
void add_calibrate_command(CLI::App& app, Action& run);
void add_table_command(CLI::App& app, Action& run);
void add_flash_command(CLI::App& app, Action& run);
void add_registers_command(CLI::App& app, Action& run);
void add_robot_command(CLI::App& app, Action& run);
void add_predict_command(CLI::App& app, Action& run);
void add_payload_command(CLI::App& app, Action& run);
void add_export_command(CLI::App& app, Action& run);
void add_monitor_command(CLI::App& app, Action& run);
/// Adds every subcommand above but add_survey_command to `app` (the dyncal program's, and the Python
/// module's; the module has no `survey`: it runs commands with --report, which the study lacks).
void add_commands(CLI::App& app, Action& run);
/// A program's command line: a CLI::App with the subcommands `add` adds (one of them required),
/// argv parsed into it and the chosen action run. A parse error is CLI11's message (exit 2, 0 for
/// --help); InputError is one line "dyncal: error: ..." (exit 2); any other exception one line
/// "dyncal: internal error: ..." (exit 1). The main() of dyncal and of dyncal-survey.
int run_cli(void (*add)(CLI::App&, Action&), int argc, char** argv);
/// `survey`'s one-line help, as dyncal lists it and dyncal-survey prints it.
inline constexpr const char* kSurveyHelp =
    "reproduce the survey's simulation study (Sec. 6: Tables 5, 6, 8-12, Fig. 4) next to its numbers";

/// Runs codegen/import_urdf.py (the URDF work: import, check, export; orocos-kdl checks) with `args`
/// under the Debian python3; its messages go straight to our stdout/stderr. Returns its exit code;
/// throws InputError when it cannot be run.
int run_urdf_tool(const std::vector<std::string>& args);

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
