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
  int joint = 0;              ///< 0-based
  int joint2 = 0;             ///< coupling only: the second joint turning the motor (0-based)
  int sign = 1;               ///< coupling only: the motor turns with q_joint + r q_joint2, r = sign * ratio
  double shape = 0;           ///< stribeck: velocity scale [rad/s]; position_periodic: cycles per revolution;
                              ///< coupling: the ratio |r| (0: 1)
  std::string variable;       ///< shape only: the spline's variable (ShapeVariable's names: "q3", "sgn(qd2)*t")
  std::vector<double> knots;  ///< shape only: the spline's full knot vector (spline_basis.hpp), boundaries 4 times
  /// shape only: the roughness penalty lambda >= 0 [unit(x)^3] of a penalised regression spline (0:
  /// none): a fit adds n_j lambda times the integral of the shape's f''(x)^2 (shape_roughness_rows) to
  /// its joint j's residual sum of squares, n_j that joint's fitted rows, both weighed alike (WLS).
  double penalty = 0;
};

/// The variable a shape effect's spline is of, on joint `joint` (0-based): its name as the diagnosis
/// and a model item write it (1-based joints) is t (seconds since the log's first kept sample), qK,
/// qdK, qddK [rad, rad/s, rad/s^2 or m for a prismatic joint] of any joint K, tau_modelJ (the model's
/// torque of the shape's own joint J without the shape, [Nm]), or sgn(qdJ)*X with X one of t, qJ,
/// tau_modelJ (the friction sign of the shape's joint times X, filtered in time as friction columns
/// are).
struct ShapeVariable {
  enum class Of { time, q, qd, qdd, tau_model };
  Of of = Of::time;
  int joint = 0;            ///< 0-based: whose q, qd, qdd or tau_model
  bool times_sign = false;  ///< times sgn(qd) of the shape's joint
};

/// Whether a shape's columns leave out the constant and the linear part of its variable
/// (spline_basis.hpp's shape_basis without_linear): a shape of tau_model, whose linear part would
/// scale every parameter of the model (its sign product's is load friction's form, kept).
inline bool shape_without_linear(const ShapeVariable& v) {
  return v.of == ShapeVariable::Of::tau_model && !v.times_sign;
}

/// shape_without_linear of the variable named `variable` (a well-formed name: tau_modelJ).
inline bool shape_without_linear(const std::string& variable) {
  return variable.rfind("tau_model", 0) == 0;
}

/// Whether the shape variable named `variable` is time (t or sgn(qdJ)*t): a change over its log, not
/// a property of the arm. sgn(qdJ)*tau_modelJ is not: only a name ending in ")*t" is.
inline bool shape_of_time(const std::string& variable) {
  const std::string& v = variable;
  return v == "t" || (v.size() > 3 && v.compare(v.size() - 3, 3, ")*t") == 0);
}

/// Whether e is a shape of time (shape_of_time of its variable).
inline bool shape_of_time(const ModelEffect& e) {
  return e.kind == EffectKind::shape && shape_of_time(e.variable);
}

/// Whether e is a shape of tau_model or its sign product (its variable reads the model's own torque).
inline bool shape_of_tau_model(const ModelEffect& e) {
  return e.kind == EffectKind::shape && e.variable.find("tau_model") != std::string::npos;
}

/// The ShapeVariable named `name` for a shape on joint `joint` (0-based) of an N-joint arm. Throws
/// InputError naming the variable: not one of ShapeVariable's forms, a joint outside 1..N, a
/// tau_model or sign of another joint than the shape's.
ShapeVariable parse_shape_variable(const std::string& name, int joint, int num_joints);

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
/// `coupling:5+6` (or `5-6`; `coupling:6+5:0.5` for a ratio other than 1), `shape:3:q3:K0/K1/.../Kn`
/// (a shape's variable and its distinct knots, the boundaries K0 and Kn once), then `:LAMBDA` for a
/// penalised one (`shape:3:q3:K0/.../Kn:0.0021`). Numbers written with
/// 17 significant digits (read back exactly).
std::string effect_item(const ModelEffect& e);

/// Parameter names of the effect's columns, as the diagnosis names them (1-based joints):
/// Fs3 | Fc+3 Fv+3 | Fp3 | Fl3 | Ia3 | offset3 | A3_sin A3_cos | Fc5+6 Fv5+6 Ia5+6 |
/// shape3_q3_2 .. shape3_q3_<knots - 4> (a shape's basis functions 2.. of its variable; sgn(qd3)*t is
/// tagged sgn_t; a shape of tau_model3 has shape_basis_columns' count, tau_model3_1 ..).
std::vector<std::string> effect_param_names(const ModelEffect& e);

/// The effect as a parameter-table term (lib/ EffectTerm) with its fitted coefficients
/// (effect_param_names' count of them, in that order), stored as float.
EffectTerm effect_term(const ModelEffect& e, const double* coefficients);

/// Parses a model string for an N-joint robot: parse_model's items (eq7, eq8, coulomb, viscous,
/// power, rotor_inertia, offset) and effect items `KIND:JOINTS[:SHAPE]` as effect_item writes
/// them, and coupled motors `coupled_motor:M+J[:RATIO]` as coupled_motor_item writes them. Throws
/// InputError naming the item: unknown kind, joint out of 1..N, a shape missing, not positive or not
/// allowed for the kind, a shape item malformed, a coupling of a joint with itself, the same effect twice,
/// rotor_inertia:J or offset:J when the terms already give every joint one, a motor coupled twice, a coupled motor
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
/// "effects" list: kind, joints, shape, sign, a shape's variable and knots; no terms). Drift has no
/// model term: skipped, and a line saying so goes to *skipped; so does one for a shape of the same
/// variable on the same joint found twice (one shape on the union of their knots, the smaller of
/// their penalties: the one that constrains neither). A shape's "penalty" is optional (0). A torque delay
/// (its delay in "shape", seconds) goes to *delays (skipped and named when delays is null). Throws
/// InputError naming the file and entry: unreadable, not JSON, not a diagnosis report, an unknown
/// kind, joints out of range, a delay that is not finite, a shape whose variable or knots are
/// malformed.
ModelSpec read_diagnosed_effects(const std::string& path, int num_joints, std::vector<std::string>* skipped,
                                 std::vector<TorqueDelay>* delays = nullptr);

}  // namespace dyncal::host
