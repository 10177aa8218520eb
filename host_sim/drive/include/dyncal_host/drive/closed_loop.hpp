#pragma once
// One run of a trajectory on the simulated drive without its transport, as a closed-loop
// simulation: the drive's known control law (PD gains, the active table's feed-forward) on a plant
// whose parameters the caller chooses. The survey's data and IDIM-IV's instruments (Gautier,
// Janot and Vandanjon 2013) both come from it.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "dyncal_host/common/drive_law.hpp"
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

/// IDIM-IV's closed loop (Gautier, Janot and Vandanjon 2013): `law`'s run on the simulated drive of
/// `robot` with a plant of standard parameters `phi_standard` (10 N) and Eq. 7 friction Fc [Nm],
/// Fv [Nm s/rad] per joint, noise-free (no torque noise, no encoder quantisation: the instruments
/// are the model's states), with the law's gains, feed-forward table and control rate. Returns the
/// plant's q [rad] at the times `t` [s] (t = 0 at the trajectory's start; rows of t, N columns),
/// interpolated linearly between the law's samples. Throws InputError naming law.source for a time
/// outside the run, or as play_closed_loop.
Eigen::MatrixXd play_law(const RobotDescription& robot, const DriveLaw& law, const Eigen::VectorXd& t,
                         const Eigen::VectorXd& phi_standard, const Eigen::VectorXd& Fc, const Eigen::VectorXd& Fv);

}  // namespace dyncal::host
