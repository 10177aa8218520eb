#pragma once
// Effect terms of an identification model beyond the compiled term set: the terms `dyncal diagnose`
// adds (lib/ effect_terms.hpp), named in `--model` as the diagnosis names them, so that a diagnosed
// model can be fitted, reported, predicted and flashed like a declared one.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "dyncal/effect_terms.hpp"
#include "dyncal_host/common/robot_description.hpp"

namespace dyncal::host {

/// One effect term with its fixed shape; its coefficients are fitted (EffectKind's c0..c2).
struct ModelEffect {
  EffectKind kind = EffectKind::offset;
  int joint = 0;     ///< 0-based
  int joint2 = 0;    ///< coupling only: the second joint turning the motor (0-based)
  int sign = 1;      ///< coupling only: the motor turns with q_joint + r q_joint2, r = sign * ratio
  double shape = 0;  ///< stribeck: velocity scale [rad/s]; position_periodic: cycles per revolution;
                     ///< coupling: the ratio |r| (0: 1)
};

/// A motor that turns with two joints in place of joint `motor`'s own (a coupled wrist: the TX40's
/// motor 6 turns with q6 + q5): its velocity is qd_motor + ratio qd_with [rad/s, joint units], and
/// the model's friction and rotor-inertia columns of joint `motor` become this motor's, acting on
/// joint `motor` and ratio times on joint `with` (the transmission's transpose). No columns of its
/// own: it changes the motor-velocity map (motor_velocity_map) as a robot.json coupling does.
struct CoupledMotor {
  int motor = 0;       ///< 0-based: the joint whose motor this is
  int with = 0;        ///< 0-based: the other joint that turns it
  double ratio = 1.0;  ///< signed, non-zero
};

/// A model: the compiled terms (dyncal::term bits), the effect terms after them, and coupled motors.
struct ModelSpec {
  unsigned terms = 0;
  std::vector<ModelEffect> effects;
  std::vector<CoupledMotor> motors;
};

/// A joint's torque channel lagging its position channel (dyncal diagnose's torque_delay): the log's
/// tau_j(t) is the joint's torque at t - seconds. Undone on the log before identification
/// (logs/torque_delay.hpp), not a model term.
struct TorqueDelay {
  int joint = 0;       ///< 0-based
  double seconds = 0;  ///< positive: the torque lags
};

/// "J:SECONDS[,J:SECONDS...]" (1-based joints, each at most once) as TorqueDelay entries. Throws
/// InputError naming the item: not J:SECONDS, a joint outside 1..num_joints or repeated, a delay
/// that is not finite.
std::vector<TorqueDelay> parse_torque_delays(const std::string& text, int num_joints);

/// The coupled motor as a `--model` item (1-based joints): `coupled_motor:6+5` (ratio 1),
/// `coupled_motor:6-5:0.5` (ratio -0.5); the ratio's magnitude written with 17 significant digits.
std::string coupled_motor_item(const CoupledMotor& m);

/// Motor velocities in joint units, v = T qd (N x N): T = diag(N)^-1 N of robot.json's transmission N
/// when `robot_transmission` (a robot without one, or with a zero gear ratio: identity), else
/// identity; then each of `motors` replaces its motor's row by e_motor + ratio e_with.
Eigen::MatrixXd motor_velocity_map(const RobotDescription& robot, bool robot_transmission,
                                   const std::vector<CoupledMotor>& motors);

/// The diagnosis's name of a kind: stribeck, asymmetric_friction, velocity_power, load_friction,
/// rotor_inertia, offset, position_periodic, coupling.
const char* effect_kind_name(EffectKind k);

/// The effect as a `--model` item (1-based joints): `stribeck:3:0.05`, `asymmetric_friction:2`,
/// `velocity_power:1`, `load_friction:2`, `rotor_inertia:4`, `offset:1`, `position_periodic:3:2`,
/// `coupling:5+6` (or `5-6`; `coupling:6+5:0.5` for a ratio other than 1). Shapes written with 17 significant digits
/// (read back exactly).
std::string effect_item(const ModelEffect& e);

/// Parameter names of the effect's columns, as the diagnosis names them (1-based joints):
/// Fs3 | Fc+3 Fv+3 | Fp3 | Fl3 | Ia3 | offset3 | A3_sin A3_cos | Fc5+6 Fv5+6 Ia5+6.
std::vector<std::string> effect_param_names(const ModelEffect& e);

/// The effect as a parameter-table term (lib/ EffectTerm) with its fitted coefficients
/// (effect_param_names' count of them, in that order), stored as float.
EffectTerm effect_term(const ModelEffect& e, const double* coefficients);

/// Parses a model string for an N-joint robot: parse_model's items (eq7, eq8, coulomb, viscous,
/// power, rotor_inertia, offset) and effect items `KIND:JOINTS[:SHAPE]` as effect_item writes
/// them, and coupled motors `coupled_motor:M+J[:RATIO]` as coupled_motor_item writes them. Throws
/// InputError naming the item: unknown kind, joint out of 1..N, a shape missing, not positive or not
/// allowed for the kind, a coupling of a joint with itself, the same effect twice, rotor_inertia:J
/// or offset:J when the terms already give every joint one, a motor coupled twice, a coupled motor
/// without friction terms in the model.
ModelSpec parse_model_spec(const std::string& model, int num_joints);

/// Whether `spec` already has `e` (the same kind, joints and shape; rotor_inertia and offset also
/// when the terms give every joint one).
bool model_contains(const ModelSpec& spec, const ModelEffect& e);

/// Appends `e` to spec.effects. Throws InputError naming `where` when model_contains(spec, e).
void add_effect(ModelSpec& spec, const ModelEffect& e, const std::string& where);

/// model_name(terms) followed by the effects' items and the coupled motors' items, comma-separated.
std::string model_spec_name(const ModelSpec& spec);

/// The effects and coupled motors of a `dyncal diagnose --report` file for an N-joint robot (its
/// "effects" list: kind, joints, shape, sign; no terms). Drift and a shape have no model term: they
/// are skipped and named in *skipped. A torque delay (its delay in "shape", seconds) goes to *delays
/// (skipped and named when delays is null). Throws InputError naming the file and entry:
/// unreadable, not JSON, not a diagnosis report, an unknown kind, joints out of range, a delay that
/// is not finite.
ModelSpec read_diagnosed_effects(const std::string& path, int num_joints, std::vector<std::string>* skipped,
                                 std::vector<TorqueDelay>* delays = nullptr);

}  // namespace dyncal::host
