#pragma once
// The robot-specific half of the simulated drive: the generated model of one robot (fixed-size
// Eigen types, N joints) as the drive runs it — forward dynamics (RK4 on M(q) qdd = tau - h(q, qd) -
// friction - effects), the control law's feed-forward from the active table, the table check, the
// nominal table and the true parameters of a scenario. One implementation per robot folder
// (DrivePlantOf<Robot>, drive_plant_of.hpp) registers itself by name when the program starts
// (host_sim/robots/); SimulatedDrive looks its robot up here.

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "dyncal/drive/monitor_settings.hpp"
#include "dyncal/drive/payload_run.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal/parameter_table.hpp"
#include "dyncal_host/common/excitation_trajectory.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/drive/ground_truth.hpp"
#include "dyncal_host/drive/scenario.hpp"

namespace dyncal::host {

/// The trajectory as the register map carries it (modbus_map::kMaxJoints slots; the drive plays
/// its robot's joints, the first slots).
using DriveTrajectory = ExcitationTrajectory;
/// One value per joint, joint 1 first; entries past the robot's joints are 0.
using JointArray = std::array<double, kMaxDriveJoints>;

/// A drive trip: which limit, the 0-based joint, the measured value that broke it.
struct Trip {
  modbus_map::DriveFault fault = modbus_map::DriveFault::none;
  int joint = 0;
  double value = 0;
};

/// One control period's numbers (SI units, joint side).
struct PlantStep {
  Trip trip;                          ///< a trip stops the period before the control law; the rest is then unset
  JointArray q_meas{}, qd_meas{};     ///< quantised encoder position, its backward difference
  JointArray tau_ff{}, tau_cmd{};     ///< feed-forward of the active table; commanded torque (+ PD)
  JointArray q{}, qd{}, qdd{};        ///< the exact plant state at the period's start
  JointArray q_d{}, qd_d{}, qdd_d{};  ///< the trajectory's state the feed-forward was computed at
  /// While the payload is identified: the active table's torque at the measured position with the
  /// trajectory's velocity and acceleration (the arm model where the arm is, not where it should be)
  JointArray tau_model{};
};

/// The drive's collision monitor (docs/monitor.md "On the drive"): lib/'s momentum observer on the
/// active table at the control rate, fed the measured q and torque through lib/'s centred slope
/// (D = round(1 / (K dt)) samples: it judges the state D control periods back); the settings and
/// their rule are the drive application's (dyncal/drive/monitor_settings.hpp).
using MonitorSettings = drive::MonitorSettings;
static_assert(std::is_same_v<JointArray, decltype(MonitorSettings::threshold)>, "one joint array");

/// lib/'s check_monitor_settings as one line: empty when the settings are taken, else why not.
std::string monitor_settings_error(const MonitorSettings& m, double dt);

class DrivePlant {
 public:
  virtual ~DrivePlant() = default;
  virtual std::uint32_t robot_id() const = 0;
  virtual int num_joints() const = 0;
  virtual int num_standard() const = 0;
  /// Format-independent checks of a decoded table: robot id, a model this drive runs (the built
  /// term sets, model_terms.hpp), parameter count and values (check_table).
  virtual TableStatus check(const ParameterTable& table) const = 0;
  /// The table of the nominal (CAD) base parameters with Eq. 7 friction Fc [Nm], beta [Nm s/rad].
  virtual ParameterTable nominal_table(const JointArray& Fc, const JointArray& beta) const = 0;
  /// ground_truth.hpp's true_parameters for this robot.
  virtual std::vector<TrueParameter> true_parameters(const Scenario& scenario, unsigned terms) const = 0;
  /// Limits, encoder resolution and rotor inertia from the robot file and the scenario.
  virtual void configure(const RobotDescription& robot, const Scenario& scenario) = 0;
  /// Standard parameters of the plant (num_standard(), generated order). Throws InputError on a size mismatch.
  virtual void set_plant_parameters(const std::vector<double>& phi_standard) = 0;
  /// The feed-forward model of `table`, which passed check().
  virtual void set_active(const ParameterTable& table) = 0;
  /// Puts the plant on the trajectory at t = 0; unless the gains are fixed, PD gains from M(q0)
  /// (natural frequency bandwidth_hz, damping of the scenario).
  virtual void begin(const DriveTrajectory& trajectory, const Scenario& scenario, bool gains_fixed, double dt) = 0;
  /// One control period at `time` (the trajectory's clock; `clock`: time since the drive started,
  /// for warm-up effects): measure, check limits, control law, then integrate the plant by dt.
  virtual PlantStep step(const DriveTrajectory& trajectory, const Scenario& scenario, const ParameterTable& active,
                         double time, double clock, double dt) = 0;
  /// Starts the payload estimator for a run (no load, diffuse prior).
  virtual void begin_payload() = 0;
  /// One recorded sample of the run: the state q_meas, qd_d, qdd_d of p and the measured torque
  /// [Nm]; the residual tau_measured - p.tau_model is the payload's torque (at the measured
  /// position: the PD loop lets a load pull the arm off the trajectory, and the arm's gravity there
  /// differs from the feed-forward's by about G' e, a bias of G' / kp on the payload); r: the torque
  /// measurement's variance per joint [Nm^2] (> 0). A sample the filter refuses is skipped.
  virtual void update_payload(const PlantStep& p, const JointArray& tau_measured, const JointArray& r) = 0;
  /// The payload run's estimate now, with its verdicts (lib/ drive/payload_run.hpp).
  virtual drive::PayloadVerdict payload_verdict() const = 0;
  /// `active` with the payload of `v` on the last link: its base parameters moved by K_N dphi
  /// (Gautier's base map of link N; the parameters v does not determine held at 0), every other
  /// value kept.
  virtual ParameterTable loaded_table(const ParameterTable& active, const drive::PayloadVerdict& v) const = 0;
  /// Turns the collision monitor on (gain > 0) or off for the runs begun after it (dt: the control
  /// period [s]). An empty string when taken, else why not (K dt above 1, a velocity window longer
  /// than the drive's, a threshold, mean or band not finite or negative). A run whose active table
  /// the observer cannot take is not watched: monitor_state() refused.
  virtual std::string set_monitor(const MonitorSettings& m, double dt) = 0;
  /// One control period's monitor step with the period's measured torque [Nm] (after step(), which
  /// did not trip): a collision trip (joint 0-based, value r_j - mean_j [Nm]) or none.
  virtual Trip monitor(const PlantStep& p, const JointArray& tau_measured) = 0;
  /// The observer's last residual r - mean [Nm] (0 while the monitor is off or filling its window).
  virtual JointArray monitor_residual() const = 0;
  /// What the last step widened each threshold by: the friction the model cannot know [Nm]
  /// (lib/ friction_uncertainty.hpp's weight times the active table's |Fc_j|).
  virtual JointArray monitor_widening() const = 0;
  /// Whether the run begun last is watched (refused: the observer cannot take the active table).
  virtual modbus_map::MonitorState monitor_state() const = 0;
  /// tau = J_p(q)^T F [Nm] of the force F [N, base frame] on `point` [m, link frame] of the 1-based
  /// `link` at q [rad] (contact_force.hpp, with this robot's generated joint origins).
  virtual JointArray contact_torque(const JointArray& q, int link, const std::array<double, 3>& point,
                                    const std::array<double, 3>& force) const = 0;
  virtual void fix_gains(const JointArray& kp, const JointArray& kd) = 0;
  virtual JointArray kp() const = 0;
  virtual JointArray kd() const = 0;
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
