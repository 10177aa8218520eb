#include "dyncal_host/drive/drive_plant.hpp"

#include <cmath>
#include <map>

#include "dyncal/centred_slope.hpp"
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
  if (!std::isfinite(m.gain) || !(m.gain >= 0)) return "the observer gain must be 0 (off) or a number > 0";
  if (m.gain > 0) {
    if (!(m.gain * dt <= 1.0))
      return "observer gain " + std::to_string(m.gain) + " 1/s: the discrete observer needs K dt <= 1";
    if (centred_slope_half_width(m.gain, dt) > modbus_map::kMonitorMaxHalfWidth)
      return "observer gain " + std::to_string(m.gain) + " 1/s: its velocity window is longer than the drive's " +
             std::to_string(2 * modbus_map::kMonitorMaxHalfWidth + 1) + " samples";
  }
  for (size_t j = 0; j < m.threshold.size(); ++j) {
    if (!std::isfinite(m.threshold[j]) || !std::isfinite(m.mean[j]) || !std::isfinite(m.band[j]) ||
        m.threshold[j] < 0 || m.band[j] < 0)
      return "joint " + std::to_string(j + 1) + ": threshold and band must be numbers >= 0, the mean a number";
  }
  return {};
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
