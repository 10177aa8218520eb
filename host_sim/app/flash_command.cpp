// dyncal flash: a parameter file (dyncal identify --params) onto a drive over Modbus.
#include <cmath>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/model_terms.hpp"
#include "dyncal_host/identification/compiled_robot.hpp"

namespace dyncal::app {
namespace {

struct FlashSettings {
  std::string uri = "tcp://127.0.0.1:1502", robot, params;
  bool reset_fault = false;
};

int run_flash(const FlashSettings& s) {
  using host::InputError;
  const nlohmann::json j = read_json_file(s.params);
  if (j.value("format", "") != "dyncal-parameters") throw InputError(s.params + ": not a dyncal parameter file");
  if (!j.contains("robot") || !j["robot"].is_string()) throw InputError(s.params + ": 'robot' missing");
  const std::string robot = j["robot"].get<std::string>();
  if (!s.robot.empty() && robot != s.robot)
    throw InputError(s.params + ": parameters are for robot '" + robot + "', not '" + s.robot + "'");
  // The table carries the id of the robot the parameters were identified for: the drive refuses it
  // (wrong robot) unless it runs that robot.
  const host::CompiledRobot& compiled = host::compiled_robot(robot);
  ParameterTable t;
  t.robot_id = compiled.robot_id;
  if (!j.contains("model") || !j["model"].is_string()) throw InputError(s.params + ": 'model' missing");
  t.model_id = host::parse_model(j["model"].get<std::string>());
  // The values are the identified parameters of that robot and model, in their order: checked by
  // name, so that a file edited by hand or written for another model cannot flash shifted values.
  const std::vector<std::string> names =
      compiled.param_names[static_cast<size_t>(host::built_term_set_index(t.model_id))]();
  if (!j.contains("params") || !j["params"].is_array()) throw InputError(s.params + ": 'params' missing");
  const auto& p = j["params"];
  if (p.size() != names.size())
    throw InputError(s.params + ": " + std::to_string(p.size()) + " params, robot '" + robot + "' with model '" +
                     j["model"].get<std::string>() + "' has " + std::to_string(names.size()));
  if (p.size() > kTableMaxParams) throw InputError(s.params + ": more params than a table holds");
  t.count = static_cast<std::uint16_t>(p.size());
  for (size_t i = 0; i < p.size(); ++i) {
    const auto& v = p[i];
    const std::string where = s.params + ": params[" + std::to_string(i + 1) + "]";
    if (!v.is_object() || !v.contains("value") || !v["value"].is_number())
      throw InputError(where + ": expected an object with a number 'value'");
    if (!v.contains("name") || !v["name"].is_string()) throw InputError(where + ": 'name' missing");
    if (v["name"].get<std::string>() != names[i])
      throw InputError(where + " is '" + v["name"].get<std::string>() + "', parameter " + std::to_string(i + 1) +
                       " of robot '" + robot + "' with model '" + j["model"].get<std::string>() + "' is '" + names[i] +
                       "'");
    const double value = v["value"].get<double>();
    if (!std::isfinite(value) || std::fabs(value) > 3.4e38)
      throw InputError(where + " '" + names[i] + "': value " + v["value"].dump() + " is not a finite float");
    t.values[i] = static_cast<float>(value);
  }
  auto d = connect_drive(s.uri);
  if (s.reset_fault && d->reset() != port::PortStatus::ok) throw InputError("reset failed: " + d->error());
  TableStatus reason = TableStatus::ok;
  const auto st = d->write(t, &reason);
  if (st == port::PortStatus::rejected) {
    std::cerr << "dyncal: the drive rejected the table: " << to_string(reason) << "; its active table is unchanged\n";
    return 3;
  }
  if (st != port::PortStatus::ok) throw InputError("flash failed: " + d->error());
  std::cout << "flashed " << t.count << " parameters; read back and compared: identical\n";
  return 0;
}

}  // namespace

void add_flash_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<FlashSettings>();
  auto* cmd = app.add_subcommand("flash", "flash a parameter file (dyncal identify --params) to the drive");
  cmd->add_option("--drive", s->uri)->capture_default_str();
  cmd->add_option("--robot", s->robot, "robot the drive runs (default: the parameter file's)");
  cmd->add_option("--params", s->params, "parameter JSON from dyncal identify --params")->required();
  cmd->add_flag("--reset-fault", s->reset_fault, "clear a drive fault first (a drive in fault takes no table)");
  cmd->callback([&run, s] { run = [s] { return run_flash(*s); }; });
}

}  // namespace dyncal::app
