#pragma once
// What the simulated drive simulates: friction per joint (survey Eq. 4-9), effects the
// identification model may not declare, noise, control and timing. Loaded from a JSON scenario
// file (schema in docs/modbus.md); every field has a default.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "dyncal/drive/stop_and_go.hpp"
#include "dyncal/joint_capacity.hpp"
#include "dyncal_host/common/friction_model.hpp"
#include "dyncal_host/common/robot_description.hpp"

namespace dyncal::host {

/// Joints a simulated drive can have (the register map's).
inline constexpr int kMaxDriveJoints = kMaxRobotJoints;
/// Torque noise of a robot without a drive.json: this fraction of each joint's tau_max [Nm].
inline constexpr double kDefaultNoiseFractionOfTauMax = 0.005;

/// Friction of one joint. Eq. 7: Fc sgn(qd) + beta qd. Eq. 4: [Fc + (Fs - Fc) exp(-|qd/qds|^delta_s)]
/// sgn(qd) + beta qd. Eq. 5: f1 sgn - f2 sgn exp(-|qd|/f3) - f4 sgn exp(-1/(f5 |qd|)) + beta qd.
/// Eq. 6: (f1 + f2 sech(f3 qd)) tanh(f4 qd) + beta qd. Eq. 8: Eq. 7 + fp qd^(1/3). Eq. 9: Eq. 7 +
/// fl |tau_load| sgn(qd) (as dyncal's Eq. 9 column). Units: Nm, Nm s/rad, rad/s.
struct JointFriction {
  FrictionModel model = FrictionModel::eq7;
  double Fc = 0, beta = 0, Fs = 0, qds = 0.1, delta_s = 2.0;
  double f1 = 0, f2 = 0, f3 = 1, f4 = 0, f5 = 1;
  double fp = 0, fl = 0;
};

/// Effects on one joint beyond its friction model.
struct JointEffects {
  double cogging_amplitude = 0;      ///< [Nm] A sin(n q + phase)
  double cogging_cycles = 0;         ///< n, cycles per joint revolution
  double cogging_phase = 0;          ///< [rad]
  double load_friction = 0;          ///< extra fl |tau_load| sgn(qd) [-] (load-dependent friction)
  double viscous_drift = 0;          ///< relative rise of beta when warm: beta (1 + d (1 - exp(-t/T)))
  double drift_time_constant = 600;  ///< T [s] (temperature time constant)
  double offset = 0;                 ///< constant torque offset in the measured torque [Nm]
  double rotor_inertia = 0;          ///< Ia, reflected to the joint side [kg m^2]
};

/// A motor that turns with q_i + sign q_j (a coupled wrist transmission): its friction
/// Fc sgn(v) + beta v, v = qd_i + sign qd_j, acts on joint i and, with the sign, on joint j.
struct CoupledFriction {
  int joint_i = 0, joint_j = 0;  ///< 0-based
  double sign = 1.0;
  double Fc = 0, beta = 0;
};

/// Motor velocities in joint units, v = T qd: row m is motor m's (kMaxDriveJoints x kMaxDriveJoints,
/// the first num_joints rows and columns used).
using MotorMap = std::array<std::array<double, kMaxDriveJoints>, kMaxDriveJoints>;

/// The identity map: every motor turns with its own joint alone.
MotorMap identity_motor_map();

/// An external contact on the arm (docs/monitor.md "On the drive"): a force on a point of a link
/// for a time window of the run's time (sim_time; with stop_and_go not the trajectory's clock).
/// Its joint torques are J_p(q)^T F, J_p the point's translational Jacobian at the plant's exact q
/// at each control period's start, held over the period as the command is (zero-order hold); with
/// `stiffness` > 0 the force grows as the point presses into a stiff obstacle instead:
/// F = -stiffness (d . n) n while d . n < 0, d the point's displacement from where it was at
/// `start`, n the unit of `force` (its direction: the obstacle pushes back along it), and `force`'s
/// magnitude is unused.
struct ExternalContact {
  int link = 1;                   ///< 1-based link (the link joint `link` moves)
  std::array<double, 3> point{};  ///< [m] in that link's frame (the generated frames, robot.json)
  std::array<double, 3> force{};  ///< [N] in the base frame
  double start = 0;               ///< [s] run time
  double duration = 0;            ///< [s]
  double stiffness = 0;           ///< [N/m]; 0: a force of fixed size
};

/// Per joint, joint 1 first; entries past num_joints are unused. friction[m] and
/// effects[m].rotor_inertia are motor m's: its friction acts at its velocity v_m = (T qd)_m and its
/// torque on every joint j by T(m, j) (the transmission's transpose); its rotor inertia Ia_m adds
/// Ia_m T_m^T T_m to the mass matrix. With the identity map (a robot without coupled motors) they
/// are joint m's. The other effects are per joint.
struct Scenario {
  std::string robot;  ///< the robot it is for (default_scenario sets it; the drive checks it)
  int num_joints = 6;
  std::uint64_t seed = 1;
  double control_rate_hz = 1000;  ///< control and integration step (RK4, `substeps` per step)
  int substeps = 2;
  double sample_rate_hz = 1000;  ///< recording rate (a divisor of the control rate)
  double bandwidth_hz = 8;       ///< PD loop natural frequency per joint (gains from M(q0))
  double damping = 1.0;
  std::array<double, kMaxDriveJoints> tau_noise_std{};  ///< torque measurement noise [Nm]
  double encoder_counts = 131072;                       ///< per motor revolution (quantisation: 2 pi / (counts N_j))
  std::array<JointFriction, kMaxDriveJoints> friction{};
  std::array<JointEffects, kMaxDriveJoints> effects{};
  std::vector<CoupledFriction> couplings;
  MotorMap motor_map = identity_motor_map();  ///< T: robot.json's transmission (motor_velocity_map)
  /// A load rigidly fixed to the last link of the plant (not of any table): mass [kg], centre of
  /// mass [m] and inertia about it [kg m^2, ixx ixy ixz iyy iyz izz] in the last link's frame;
  /// mass 0: none. Added to the plant's standard parameters (docs/payload.md "On the drive").
  struct Payload {
    double mass = 0;
    std::array<double, 3> com{};
    std::array<double, 6> inertia{};
  } payload;
  std::vector<ExternalContact> contacts;  ///< none by default
  /// Point-to-point operation: the trajectory played in moves with stops between (off by default;
  /// its clock drives the reference q_d, qd_d = w qd(u), qdd_d = w^2 qdd(u) + w' qd(u)); a run
  /// plays the trajectory's periods on that clock, so it lasts longer by the rests.
  drive::StopAndGo stop_and_go;
  /// Static friction (off by default: the survey's friction laws are kinetic): a motor whose
  /// velocity reaches zero stays at rest while the torque that holds it there lies within its
  /// friction's values just above and below zero velocity, friction(+0) and friction(-0) (Fs for
  /// Eq. 4, Fc for Eq. 7; with the identity map plus the load-dependent friction); otherwise it
  /// starts with that friction against it (a stick-slip law as Karnopp's, docs/modbus.md). The
  /// coupled frictions (`couplings`) stay kinetic.
  bool stiction = false;
};

/// The default scenario for `robot`: robot.json's transmission as the motor map (a coupled motor,
/// such as the TX40's motor 6 on q5 + q6, simulated as the motor it is); Eq. 7 friction with the robot file's Fc and
/// beta; from the folder's optional drive.json (docs/robots.md) the motor inertias J_m [kg m^2] (reflected rotor
/// inertia Ia = J_m N^2, N the gear ratio; none without the file) and the torque noise [Nm]
/// (kDefaultNoiseFractionOfTauMax of tau_max without it); no undeclared effects. Throws InputError
/// (a malformed drive.json, a robot of more than kMaxDriveJoints joints).
Scenario default_scenario(const RobotDescription& robot);

/// Reads a scenario JSON file over the defaults of `robot`. Throws InputError naming the field.
Scenario load_scenario(const std::string& path, const RobotDescription& robot);

/// Friction torque [Nm] of one joint at velocity qd [rad/s], load torque tau_load [Nm]: the
/// simulated arm's truth, written apart from lib/'s friction laws (friction.hpp,
/// nonlinear_friction.hpp) on purpose: the tests identify those laws against this one, so a mistake
/// in either shows instead of cancelling.
double friction_torque(const JointFriction& f, double qd, double tau_load);

/// One of a scenario's true parameters, in the order of an identification model (ground_truth.hpp).
struct TrueParameter {
  std::string name;
  double value = 0;
};

}  // namespace dyncal::host
