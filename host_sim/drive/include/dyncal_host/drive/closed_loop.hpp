#pragma once
// One run of a trajectory on the simulated drive without its transport, as a closed-loop
// simulation: the drive's known control law (PD gains, the active table's feed-forward) on a plant
// whose parameters the caller chooses. The survey's data and IDIM-IV's instruments (Gautier,
// Janot and Vandanjon 2013) both come from it.

#include <cstdint>
#include <vector>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/drive/scenario.hpp"
#include "dyncal_host/drive/simulated_drive.hpp"

namespace dyncal::host {

/// Plays `trajectory` `periods` times at rate_hz samples per second on a simulated drive of `robot`
/// with `scenario` (friction, effects, noise, control rate) and the encoded table `table` active,
/// and returns the plant sample of every recorded sample (t = k / rate_hz from the trajectory's
/// start). plant_standard: the plant's 10 N standard parameters (empty: robot.json's); kp, kd: fixed
/// PD gains (nullptr: the drive's own, from M(q0)). Throws InputError when the drive refuses the table
/// or trips (the plant left the robot's limits: unstable, or far from the law's model).
std::vector<SimulatedDrive::PlantSample> play_closed_loop(const RobotDescription& robot, const Scenario& scenario,
                                                          const DriveTrajectory& trajectory, int periods,
                                                          double rate_hz, const std::vector<std::uint8_t>& table,
                                                          const std::vector<double>& plant_standard,
                                                          const JointArray* kp, const JointArray* kd);

}  // namespace dyncal::host
