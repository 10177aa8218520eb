#include "dyncal_host/drive/drive_plant.hpp"

#include <cmath>
#include <map>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {
namespace {

// Function-local static: the robots' static initialisers may run before any other of this file.
std::map<std::string, DrivePlantFactory>& registry() {
  static std::map<std::string, DrivePlantFactory> plants;
  return plants;
}

}  // namespace

std::string monitor_settings_error(const MonitorSettings& m, double dt) {
  const drive::MonitorCheck c = drive::check_monitor_settings(m, dt);
  switch (c.refusal) {
    case drive::MonitorRefusal::none:
      return {};
    case drive::MonitorRefusal::gain:
      return "the observer gain must be 0 (off) or a number > 0";
    case drive::MonitorRefusal::gain_step:
      return "observer gain " + std::to_string(m.gain) + " 1/s: the discrete observer needs K dt <= 1";
    case drive::MonitorRefusal::gain_window:
      return "observer gain " + std::to_string(m.gain) + " 1/s: its velocity window is longer than the drive's " +
             std::to_string(2 * modbus_map::kMonitorMaxHalfWidth + 1) + " samples";
    case drive::MonitorRefusal::joint:
      return "joint " + std::to_string(c.joint + 1) + ": threshold and band must be numbers >= 0, the mean a number";
  }
  return "unknown refusal";
}

bool register_drive_plant(const std::string& name, DrivePlantFactory factory) {
  registry()[name] = factory;
  return true;
}

std::unique_ptr<DrivePlant> make_drive_plant(const std::string& name) {
  const auto it = registry().find(name);
  if (it == registry().end()) {
    std::string known;
    for (const auto& [n, f] : registry()) known += (known.empty() ? "" : ", ") + n;
    throw InputError("the simulated drive has no compiled model of '" + name + "' in this build (compiled: " + known +
                     "); add robots/" + name + "/ (docs/robots.md) and build again");
  }
  return it->second();
}

std::unique_ptr<DrivePlant> make_drive_plant(const RobotDescription& robot) {
  auto plant = make_drive_plant(robot.name);
  if (plant->num_joints() != robot.num_joints)
    throw InputError(robot.directory + "/robot.json lists " + std::to_string(robot.num_joints) +
                     " joints, its compiled model has " + std::to_string(plant->num_joints()) + ": build again");
  return plant;
}

}  // namespace dyncal::host
