// dyncal flash: a parameter file (dyncal identify --params) onto a drive over Modbus.
#include <cmath>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "dyncal_host/calibration/calibrate.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/model_terms.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/model/drive_table.hpp"

namespace dyncal::app {
namespace {

struct FlashSettings {
  std::string uri = "tcp://127.0.0.1:1502", robot, params, robots_dir = host::default_robots_dir();
  bool reset_fault = false;
};

int run_flash(const FlashSettings& s) {
  using host::InputError;
  const host::ParameterSet p = host::read_parameter_file(s.params);  // names checked against the model
  if (!s.robot.empty() && p.robot != s.robot)
    throw InputError(s.params + ": parameters are for robot '" + p.robot + "', not '" + s.robot + "'");
  // The drive's form: compiled values per joint, a coupled motor's terms and the file's effects as
  // effect terms (drive_table.hpp), applied by the drive's feed-forward. The table carries the id of
  // the robot the parameters were identified for: the drive refuses it (wrong robot) unless it runs
  // that robot.
  std::vector<std::string> notes;
  ParameterTable t;
  try {
    t = host::parameter_table(p, host::load_checked_robot(s.robots_dir, p.robot), &notes);
  } catch (const InputError& e) {
    throw InputError(s.params + ": " + e.what());
  }
  for (const auto& line : notes) std::cout << "note: " << line << "\n";
  auto d = connect_drive(s.uri);
  if (s.reset_fault && d->reset() != port::PortStatus::ok) throw InputError("reset failed: " + d->error());
  TableStatus reason = TableStatus::ok;
  const auto st = d->write(t, &reason);
  if (st == port::PortStatus::rejected) {
    std::cerr << "dyncal: " << host::table_refusal(reason) << "; its active table is unchanged\n";
    return 3;
  }
  if (st != port::PortStatus::ok) throw InputError("flash failed: " + d->error());
  std::cout << "flashed " << t.count << " parameters and " << t.effect_count
            << " effect terms; read back and compared: identical\n";
  return 0;
}

}  // namespace

void add_flash_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<FlashSettings>();
  auto* cmd = app.add_subcommand("flash", "flash a parameter file (dyncal identify --params) to the drive");
  cmd->add_option("--drive", s->uri)->capture_default_str();
  cmd->add_option("--robot", s->robot, "robot the drive runs (default: the parameter file's)");
  cmd->add_option("--params", s->params, "parameter JSON from dyncal identify --params")->required();
  cmd->add_option("--robots-dir", s->robots_dir, "directory holding the robot descriptions (the transmission)");
  cmd->add_flag("--reset-fault", s->reset_fault, "clear a drive fault first (a drive in fault takes no table)");
  cmd->callback([&run, s] { run = [s] { return run_flash(*s); }; });
}

}  // namespace dyncal::app
