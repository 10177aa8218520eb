// dyncal flash: a parameter file (dyncal identify --params) onto a drive over Modbus.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/model_terms.hpp"

namespace dyncal::app {
namespace {

struct FlashSettings {
  std::string uri = "tcp://127.0.0.1:1502", robot = "er20", params;
};

int run_flash(const FlashSettings& s) {
  using host::InputError;
  const nlohmann::json j = read_json_file(s.params);
  if (j.value("format", "") != "dyncal-parameters") throw InputError(s.params + ": not a dyncal parameter file");
  auto d = connect_drive(s.uri);
  linux_port::DriveInfo info;
  if (d->read_info(info) != port::PortStatus::ok) throw InputError("drive: " + d->error());
  ParameterTable t;
  t.robot_id = info.robot_id;
  if (j.value("robot", "") != s.robot) {
    throw InputError(s.params + ": parameters are for robot '" + j.value("robot", "") + "', not '" + s.robot + "'");
  }
  t.model_id = host::parse_model(j.value("model", ""));
  const auto& p = j["params"];
  if (!p.is_array() || p.empty() || p.size() > kTableMaxParams) throw InputError(s.params + ": bad 'params'");
  t.count = static_cast<std::uint16_t>(p.size());
  for (size_t i = 0; i < p.size(); ++i) t.values[i] = p[i]["value"].get<float>();
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
  cmd->add_option("--robot", s->robot)->capture_default_str();
  cmd->add_option("--params", s->params, "parameter JSON from dyncal identify --params")->required();
  cmd->callback([&run, s] { run = [s] { return run_flash(*s); }; });
}

}  // namespace dyncal::app
