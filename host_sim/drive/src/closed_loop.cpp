#include "dyncal_host/drive/closed_loop.hpp"

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <string>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {
namespace {

/// A scratch file for the drive's simulated flash (removed again by the caller).
std::string scratch_table_path(std::uint64_t seed) {
  static std::atomic<int> counter{0};  // runs may be simulated on several threads
  return (std::filesystem::temp_directory_path() / ("dyncal_closed_loop_" + std::to_string(::getpid()) + "_" +
                                                    std::to_string(seed) + "_" + std::to_string(counter++) + ".bin"))
      .string();
}

}  // namespace

std::vector<SimulatedDrive::PlantSample> play_closed_loop(const RobotDescription& robot, const Scenario& scenario,
                                                          const DriveTrajectory& trajectory, int periods,
                                                          double rate_hz, const std::vector<std::uint8_t>& table,
                                                          const std::vector<double>& plant_standard,
                                                          const JointArray* kp, const JointArray* kd) {
  const std::string path = scratch_table_path(scenario.seed);
  std::filesystem::remove(path);
  std::vector<SimulatedDrive::PlantSample> out;
  {
    SimulatedDrive drive(robot, scenario, path);
    const TableStatus st = drive.commit(table.data(), static_cast<int>(table.size()));
    if (st != TableStatus::ok) throw InputError(std::string("the simulated drive refused the table: ") + to_string(st));
    drive.trajectory = trajectory;
    drive.periods = periods;
    drive.sample_rate_hz = rate_hz;
    drive.lockstep = false;
    if (!plant_standard.empty()) drive.set_plant_parameters(plant_standard);
    if (kp && kd) drive.fix_gains(*kp, *kd);
    drive.plant_log = &out;
    drive.start();
    while (drive.state() == modbus_map::DriveState::playing) {
      drive.step();
      if (!drive.ring().empty()) drive.ack(drive.ring().back().seq + 1);  // only the plant log is used
    }
    // A plant beyond the robot's limits has left the simulation's valid range (or is unstable):
    // the drive trips, and the record is refused instead of identified from.
    if (drive.state() == modbus_map::DriveState::fault) {
      std::filesystem::remove(path);
      throw InputError("the simulated drive stopped at t = " + std::to_string(drive.time()) + " s: joint " +
                       std::to_string(drive.fault_joint()) + " " + modbus_map::to_string(drive.fault()) + " (" +
                       std::to_string(drive.fault_value()) + ")");
    }
  }
  std::filesystem::remove(path);
  return out;
}

}  // namespace dyncal::host
