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

Eigen::MatrixXd play_law(const RobotDescription& robot, const DriveLaw& law, const Eigen::VectorXd& t,
                         const Eigen::VectorXd& phi_standard, const Eigen::VectorXd& Fc, const Eigen::VectorXd& Fv) {
  Scenario sc = default_scenario(robot);
  sc.tau_noise_std.fill(0.0);
  sc.encoder_counts = 0;
  sc.couplings.clear();
  sc.motor_map = identity_motor_map();  // the plant IDIM-IV fits: Eq. 7 friction per joint
  if (law.control_rate_hz > 0) sc.control_rate_hz = law.control_rate_hz;
  sc.sample_rate_hz = law.sample_rate_hz;
  JointArray kp{}, kd{};
  for (int j = 0; j < robot.num_joints; ++j) {
    sc.friction[j] = JointFriction{};
    sc.friction[j].model = FrictionModel::eq7;
    sc.friction[j].Fc = Fc[j];
    sc.friction[j].beta = Fv[j];
    sc.effects[j] = JointEffects{};
    kp[j] = law.kp[static_cast<size_t>(j)];
    kd[j] = law.kd[static_cast<size_t>(j)];
  }
  const auto bytes = encoded_table(law.has_table ? law.table : nominal_table(robot.name));
  const auto run =
      play_closed_loop(robot, sc, law.trajectory, law.periods, law.sample_rate_hz, bytes,
                       std::vector<double>(phi_standard.data(), phi_standard.data() + phi_standard.size()), &kp, &kd);
  Eigen::MatrixXd q(t.size(), robot.num_joints);
  const double dt = 1.0 / law.sample_rate_hz;
  for (Eigen::Index s = 0; s < t.size(); ++s) {
    const double x = t[s] / dt;
    auto k = static_cast<size_t>(std::max(0.0, std::floor(x)));
    // The run's last sample itself (a log as long as the law's run) within rounding of its time.
    if (!run.empty() && k + 1 == run.size() && x - static_cast<double>(k) < 1e-6) --k;
    if (!(t[s] >= 0.0) || k + 1 >= run.size())
      throw InputError(law.source + ": the log's t = " + std::to_string(t[s]) + " s lies outside the law's run (0.." +
                       std::to_string(dt * static_cast<double>(run.size() - 1)) +
                       " s: t = 0 at the trajectory's start)");
    const double a = x - static_cast<double>(k);
    for (int j = 0; j < robot.num_joints; ++j) q(s, j) = (1.0 - a) * run[k].q[j] + a * run[k + 1].q[j];
  }
  return q;
}

}  // namespace dyncal::host
