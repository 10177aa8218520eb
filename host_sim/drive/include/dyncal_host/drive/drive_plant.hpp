#pragma once
// The robot-specific half of the simulated drive: lib/'s drive application
// (dyncal/drive/drive_application.hpp: run control, control law, limit trips, recording, model
// error, collision monitor, payload run, the table) compiled for one robot in double, over the
// scenario's arm (scenario_arm.hpp: the generated model's forward dynamics with the scenario's
// friction and effects) and a parameter store; besides, the robot's nominal table, the true
// parameters of a scenario and contact torques. One implementation per robot folder
// (DrivePlantOf<Robot>, drive_plant_of.hpp) registers itself by name when the program starts
// (host_sim/robots/); SimulatedDrive looks its robot up here and forwards to it.

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "dyncal/drive/monitor_settings.hpp"
#include "dyncal/drive/payload_run.hpp"
#include "dyncal/drive/register_server.hpp"
#include "dyncal/drive/sample_ring.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal/parameter_table.hpp"
#include "dyncal/port.hpp"
#include "dyncal_host/common/excitation_trajectory.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/drive/scenario.hpp"

namespace dyncal::host {

/// The trajectory as the register map carries it (modbus_map::kMaxJoints slots; the drive plays
/// its robot's joints, the first slots).
using DriveTrajectory = ExcitationTrajectory;
/// One value per joint, joint 1 first; entries past the robot's joints are 0.
using JointArray = std::array<double, kMaxDriveJoints>;

/// The samples the simulated drive's ring holds at most (DrivePlant::set_ring_limit makes it
/// smaller): 1.4 MB of lib/'s packed samples, on the heap.
inline constexpr int kSimulatedRingCapacity = 16384;
using SimulatedRing = drive::SampleRing<kSimulatedRingCapacity>;

/// The exact plant state at one control period's start (simulation studies, survey Fig. 3): the
/// run's time t [s], q [rad], qd [rad/s], qdd [rad/s^2] of the plant, the commanded torque [Nm] and
/// the measured (noisy) torque [Nm] of that period.
struct PlantSample {
  double t = 0;
  JointArray q{}, qd{}, qdd{}, tau_cmd{}, tau_measured{};
};

/// The drive's collision monitor (docs/monitor.md "On the drive"): lib/'s momentum observer on the
/// active table at the control rate, fed the measured q and torque through lib/'s centred slope
/// (D = round(1 / (K dt)) samples: it judges the state D control periods back); the settings and
/// their rule are the drive application's (dyncal/drive/monitor_settings.hpp).
using MonitorSettings = drive::MonitorSettings;
static_assert(std::is_same_v<JointArray, decltype(MonitorSettings::threshold)>, "one joint array");

/// lib/'s check_monitor_settings as one line: empty when the settings are taken, else why not.
std::string monitor_settings_error(const MonitorSettings& m, double dt);

/// One robot's drive. Before configure() only the robot's data (robot_id to contact_torque) are
/// there; the rest is lib/'s DriveApplication (drive_application.hpp documents each call), joint
/// arrays holding the robot's joints first.
class DrivePlant {
 public:
  virtual ~DrivePlant() = default;
  // --- the robot
  virtual std::uint32_t robot_id() const = 0;
  virtual int num_joints() const = 0;
  virtual int num_standard() const = 0;
  /// The table of the nominal (CAD) base parameters with Eq. 7 friction Fc [Nm], beta [Nm s/rad].
  virtual ParameterTable nominal_table(const JointArray& Fc, const JointArray& beta) const = 0;
  /// ground_truth.hpp's true_parameters for this robot.
  virtual std::vector<TrueParameter> true_parameters(const Scenario& scenario, unsigned terms) const = 0;
  /// tau = J_p(q)^T F [Nm] of the force F [N, base frame] on `point` [m, link frame] of the 1-based
  /// `link` at q [rad] (contact_force.hpp, with this robot's generated joint origins).
  virtual JointArray contact_torque(const JointArray& q, int link, const std::array<double, 3>& point,
                                    const std::array<double, 3>& force) const = 0;

  // --- the drive
  /// Builds the drive: the scenario's arm, the robot file's ratings, the table in `store` (which
  /// must outlive this plant). The drive runs the term sets the host tools build (model_terms.hpp).
  virtual void configure(const RobotDescription& robot, const Scenario& scenario, port::ParameterStore& store) = 0;
  /// Standard parameters of the arm (num_standard(), generated order). Throws InputError on a size mismatch.
  virtual void set_plant_parameters(const std::vector<double>& phi_standard) = 0;
  virtual TableStatus load() = 0;
  virtual TableStatus activate(const ParameterTable& table) = 0;
  virtual const ParameterTable& active_table() const = 0;
  virtual std::vector<std::uint8_t> active_table_bytes() const = 0;
  virtual std::uint32_t table_generation() const = 0;
  virtual TableStatus commit(const std::uint8_t* bytes, int size) = 0;
  virtual bool start(modbus_map::Command c, const drive::RunSettings& run, const MonitorSettings& monitor) = 0;
  virtual void stop() = 0;
  virtual void reset() = 0;
  /// fault with 1-based `joint` (0: none) and `value` (its unit).
  virtual void trip(modbus_map::DriveFault fault, int joint, double value) = 0;
  virtual bool wants_period() const = 0;
  /// One control period (the arm's last() then holds its exact state).
  virtual void period() = 0;
  virtual const PlantSample& last_sample() const = 0;
  virtual modbus_map::DriveState state() const = 0;
  virtual modbus_map::DriveFault fault() const = 0;
  virtual int fault_joint() const = 0;
  virtual double fault_value() const = 0;
  virtual double time() const = 0;
  virtual std::uint32_t acked() const = 0;
  virtual std::uint32_t produced() const = 0;
  virtual std::uint32_t overruns() const = 0;
  virtual void ack(std::uint32_t seq_end) = 0;
  virtual const SimulatedRing& ring() const = 0;
  virtual long ring_capacity_samples() const = 0;
  virtual bool set_ring_limit(long samples) = 0;
  virtual bool set_ring_format(modbus_map::RingFormat f) = 0;
  virtual modbus_map::RingFormat ring_format() const = 0;
  virtual long run_samples(double periods, double period_s, double fs) const = 0;
  virtual void publish_inputs(std::uint16_t* input) const = 0;
  virtual void publish_window(std::uint16_t* window) const = 0;
  virtual bool fix_gains(const JointArray& kp, const JointArray& kd) = 0;
  virtual JointArray kp() const = 0;
  virtual JointArray kd() const = 0;
  virtual JointArray model_error_rms() const = 0;
  virtual modbus_map::PayloadState payload_state() const = 0;
  virtual const drive::PayloadVerdict& payload() const = 0;
  virtual modbus_map::MonitorState monitor_state() const = 0;
  virtual JointArray monitor_residual() const = 0;
  virtual JointArray monitor_widening() const = 0;
};

using DrivePlantFactory = std::unique_ptr<DrivePlant> (*)();

/// Registers robot `name`'s plant; called from static initialisers (host_sim/robots/). Returns true.
bool register_drive_plant(const std::string& name, DrivePlantFactory factory);

/// A new plant of `robot` (its joint count checked). Throws InputError listing the robots compiled
/// into this build when it is not one of them.
std::unique_ptr<DrivePlant> make_drive_plant(const RobotDescription& robot);

/// A new plant of the compiled robot `name`. Throws InputError as above.
std::unique_ptr<DrivePlant> make_drive_plant(const std::string& name);

}  // namespace dyncal::host
