#pragma once
// Effect terms of an identification model beyond the compiled term set: the terms `dyncal diagnose`
// adds (lib/ effect_terms.hpp), named in `--model` as the diagnosis names them, so that a diagnosed
// model can be fitted, reported, predicted and flashed like a declared one.

#include <string>
#include <vector>

#include "dyncal/effect_terms.hpp"

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

/// A model: the compiled terms (dyncal::term bits) and the effect terms after them.
struct ModelSpec {
  unsigned terms = 0;
  std::vector<ModelEffect> effects;
};

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
/// them. Throws InputError naming the item: unknown kind, joint out of 1..N, a shape missing, not
/// positive or not allowed for the kind, a coupling of a joint with itself, the same effect twice,
/// rotor_inertia:J or offset:J when the terms already give every joint one.
ModelSpec parse_model_spec(const std::string& model, int num_joints);

/// Whether `spec` already has `e` (the same kind, joints and shape; rotor_inertia and offset also
/// when the terms give every joint one).
bool model_contains(const ModelSpec& spec, const ModelEffect& e);

/// Appends `e` to spec.effects. Throws InputError naming `where` when model_contains(spec, e).
void add_effect(ModelSpec& spec, const ModelEffect& e, const std::string& where);

/// model_name(terms) followed by the effects' items, comma-separated.
std::string model_spec_name(const ModelSpec& spec);

/// The effects of a `dyncal diagnose --report` file for an N-joint robot (its "effects" list: kind,
/// joints, shape, sign). Drift has no model term: it is skipped and named in *skipped. Throws
/// InputError naming the file and entry: unreadable, not JSON, not a diagnosis report, an unknown
/// kind, joints out of range.
std::vector<ModelEffect> read_diagnosed_effects(const std::string& path, int num_joints,
                                                std::vector<std::string>* skipped);

}  // namespace dyncal::host
