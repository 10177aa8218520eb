#!/usr/bin/python3
"""dyncal code generator.

Usage: generate.py ROBOT_DIR OUT_DIR
Reads ROBOT_DIR/robot.json (and the URDF it names), writes OUT_DIR/{parameters,regressor,
dynamics,robot}.hpp: fixed-size, allocation-free C++17 templated on Scalar.
Output is byte-for-byte deterministic for given inputs.
"""
import hashlib
import os
import sys
import time
import types

import sympy as sp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from dyncal_codegen import base_parameters, description, dynamics  # noqa: E402
from dyncal_codegen.description import STANDARD_NAMES  # noqa: E402
from dyncal_codegen.emit_cpp import CppPrinter  # noqa: E402
from dyncal_codegen.tracer import live_program  # noqa: E402

GENERATOR_VERSION = "5"


def input_digest(robot_dir, desc):
    files = ["robot.json"]
    if desc["kinematics"]["format"] == "urdf":
        files.append(desc["kinematics"]["file"])
    h = hashlib.sha256()
    parts = []
    for f in files:
        data = open(os.path.join(robot_dir, f), "rb").read()
        h.update(data)
        parts.append(f"{f} (sha256 {hashlib.sha256(data).hexdigest()[:16]})")
    return parts


def banner(name, inputs, what, counts):
    lines = [
        "// GENERATED FILE - DO NOT EDIT.",
        f"// Generator: codegen/generate.py (dyncal codegen {GENERATOR_VERSION}, SymPy {sp.__version__})",
        f"// Robot: {name}; inputs: robots/{name}/" + f", robots/{name}/".join(inputs),
        f"// Contents: {what}",
    ]
    for fn, (m, a) in counts.items():
        lines.append(f"// Operation count {fn}: {m} multiplications, {a} additions (plus dyncal::sin_cos of q)")
    lines.append(f"// Include as \"dyncal/generated/{name}/<file>.hpp\".")
    lines.append("// Regenerate: cmake --build <build> --target regenerate (or scripts/codegen).")
    return "\n".join(lines) + "\n"


def preamble(used, n, with_q=True, with_qd=True, with_qdd=True, indent="  "):
    out = []
    for i in range(n):
        if sp.Symbol(f"q{i + 1}") in used:
            out.append(f"{indent}const Scalar q{i + 1} = q[{i}];")
        has_c, has_s = sp.Symbol(f"c{i + 1}") in used, sp.Symbol(f"s{i + 1}") in used
        if has_c or has_s:
            out.append(f"{indent}const SinCos<Scalar> sc{i + 1} = sin_cos(q[{i}]);")
        if has_c:
            out.append(f"{indent}const Scalar c{i + 1} = sc{i + 1}.cos;")
        if has_s:
            out.append(f"{indent}const Scalar s{i + 1} = sc{i + 1}.sin;")
    for i in range(n):
        if sp.Symbol(f"qd{i + 1}") in used:
            out.append(f"{indent}const Scalar qd{i + 1} = qd[{i}];")
        if sp.Symbol(f"qdd{i + 1}") in used:
            out.append(f"{indent}const Scalar qdd{i + 1} = qdd[{i}];")
    for k in range(10 * n):
        if sp.Symbol(f"phi{k}") in used:
            out.append(f"{indent}const Scalar phi{k} = phi[{k}];")
    return "\n".join(out)


def used_symbols(defs, outputs):
    used = set()
    for _, e in defs:
        used |= e.free_symbols
    for e in outputs:
        used |= sp.sympify(e).free_symbols
    return used


def body(defs, assignments, zeros=()):
    """Straight-line body: the live program with each `target = expr;` placed right after the last
    definition it reads (short live ranges: fewer register spills), then `target = 0;` for the
    structurally zero entries (cheaper than clearing the whole output first). Returns (text, muls, adds)."""
    printer = CppPrinter()
    position = {s: i for i, (s, _) in enumerate(defs)}
    after = [[] for _ in range(len(defs) + 1)]
    for target, e in assignments:
        e = sp.sympify(e)
        last = max((position[x] for x in e.free_symbols if x in position), default=-1)
        after[last + 1].append((target, e))
    lines = []
    for i in range(len(defs) + 1):
        if i > 0:
            lines.append(printer.program([defs[i - 1]]))
        for target, e in after[i]:
            lines.append(f"  {target} = {printer.expr(e)};")
    for target in zeros:
        lines.append(f"  {target} = Scalar(0);")
    return "\n".join(l for l in lines if l), printer.muls, printer.adds


def fnv1a32(text):
    h = 0x811C9DC5
    for b in text.encode():
        h = ((h ^ b) * 0x01000193) & 0xFFFFFFFF
    return h


def std_name(k):
    return f"link{k // 10 + 1}_{STANDARD_NAMES[k % 10]}"


def fmt(x):
    return repr(float(x))


def regressor_header(joints, desc, gravity, name, inputs):
    """regressor.hpp: the standard and base regressors; with the base parameters (bp), Y and the
    operation counts."""
    n = len(joints)
    n_std = 10 * n
    ns = f"dyncal::generated::{name}"
    tr, Y, sym = dynamics.standard_regressor(joints, gravity)
    flat = [Y[i][k] for i in range(n) for k in range(n_std)]
    Yfun = base_parameters.compile_program(live_program(tr.defs, flat), flat, sym)
    bp = base_parameters.compute(Yfun, n, bool(desc.get("rotor_inertia", False)))
    nb = len(bp.independent)

    vec = f"Eigen::Matrix<Scalar, {n}, 1>"
    args = f"const {vec}& q, const {vec}& qd, const {vec}& qdd"

    std_assign = [(f"Y({i}, {k})", Y[i][k]) for i in range(n) for k in range(n_std) if Y[i][k] != 0]
    std_defs = live_program(tr.defs, [e for _, e in std_assign])
    std_zeros = [f"Y({i}, {k})" for i in range(n) for k in range(n_std) if Y[i][k] == 0]
    std_text, std_m, std_a = body(std_defs, std_assign, std_zeros)
    base_assign = [(f"Yb({i}, {b})", Y[i][k]) for i in range(n) for b, k in enumerate(bp.independent) if Y[i][k] != 0]
    base_defs = live_program(tr.defs, [e for _, e in base_assign])
    base_zeros = [f"Yb({i}, {b})" for i in range(n) for b, k in enumerate(bp.independent) if Y[i][k] == 0]
    base_text, base_m, base_a = body(base_defs, base_assign, base_zeros)

    regressor_hpp = banner(name, inputs, "standard regressor Y and base regressor Y_b",
                           {"standard_regressor": (std_m, std_a), "base_regressor": (base_m, base_a)})
    regressor_hpp += f"""#pragma once

#include <Eigen/Core>

#include "dyncal/sin_cos.hpp"
#include "parameters.hpp"

namespace {ns} {{

/// Standard regressor Y ({n} x {n_std}): tau = Y(q, qd, qdd) * phi, phi the standard parameters
/// (StandardParam order; 10 per link about the link frame origin, link axes, Khalil-Kleinfinger).
/// q [rad], qd [rad/s], qdd [rad/s^2] ([m], [m/s], [m/s^2] for a prismatic joint, kJointPrismatic);
/// Y row i gives joint i+1's torque [Nm] (force [N] when prismatic). Gravity included.
/// Allocation-free; every entry of Y is written.
template <typename Scalar>
inline void standard_regressor({args}, Eigen::Matrix<Scalar, {n}, {n_std}>& Y) noexcept {{
{preamble(used_symbols(std_defs, [e for _, e in std_assign]), n)}
{std_text}
}}

/// Base regressor Y_b ({n} x {nb}) = the independent columns of Y (BaseParam order), so that
/// tau = Y_b * phi_b with phi_b = standard_to_base(phi) (Gautier 1990). Same inputs as above.
/// Writes columns 0..{nb - 1} of Yb; further columns (Cols > {nb}, e.g. friction terms) are untouched.
template <typename Scalar, int Cols>
inline void base_regressor({args}, Eigen::Matrix<Scalar, {n}, Cols>& Yb) noexcept {{
  static_assert(Cols >= {nb}, "Yb needs at least {nb} columns");
{preamble(used_symbols(base_defs, [e for _, e in base_assign]), n)}
{base_text}
}}

}}  // namespace {ns}
"""

    return regressor_hpp, bp, Y, (std_m, std_a, base_m, base_a)


def dynamics_header(joints, gravity, name, inputs):
    """dynamics.hpp: inverse dynamics (recursive Newton-Euler) and the mass matrix; with the operation
    counts."""
    n = len(joints)
    n_std = 10 * n
    ns = f"dyncal::generated::{name}"
    vec = f"Eigen::Matrix<Scalar, {n}, 1>"
    args = f"const {vec}& q, const {vec}& qd, const {vec}& qdd"
    trd, tau, _ = dynamics.inverse_dynamics(joints, gravity)
    id_assign = [(f"tau[{i}]", tau[i]) for i in range(n)]
    id_defs = live_program(trd.defs, tau)
    id_text, id_m, id_a = body(id_defs, id_assign)
    trm, M, _ = dynamics.mass_matrix(joints)
    mm_assign = []
    for (i, j), e in sorted(M.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        mm_assign.append((f"M({i}, {j})", e))
    mm_defs = live_program(trm.defs, [e for _, e in mm_assign])
    mm_text, mm_m, mm_a = body(mm_defs, mm_assign)
    mirror = "\n".join(f"  M({j}, {i}) = M({i}, {j});" for j in range(n) for i in range(j + 1, n))
    pvec = f"Eigen::Matrix<Scalar, {n_std}, 1>"
    dynamics_hpp = banner(name, inputs, "inverse dynamics tau(q, qd, qdd, phi) and mass matrix M(q, phi)",
                          {"inverse_dynamics": (id_m, id_a), "mass_matrix": (mm_m, mm_a)})
    dynamics_hpp += f"""#pragma once

#include <Eigen/Core>

#include "dyncal/sin_cos.hpp"
#include "parameters.hpp"

namespace {ns} {{

/// Inverse dynamics by recursive Newton-Euler: tau [Nm] ({n}) from q [rad], qd [rad/s], qdd [rad/s^2]
/// ([N], [m], [m/s], [m/s^2] for a prismatic joint) and the standard parameters phi ({n_std},
/// StandardParam order). Gravity included.
template <typename Scalar>
inline void inverse_dynamics({args}, const {pvec}& phi, {vec}& tau) noexcept {{
{preamble(used_symbols(id_defs, tau), n)}
{id_text}
}}

/// Joint-space mass matrix M(q) [kg m^2; kg m and kg on prismatic rows and columns] ({n} x {n},
/// symmetric) for standard parameters phi: tau = M(q) qdd + c(q, qd) + g(q). Only the lower triangle
/// is derived; the upper one is mirrored.
template <typename Scalar>
inline void mass_matrix(const {vec}& q, const {pvec}& phi, Eigen::Matrix<Scalar, {n}, {n}>& M) noexcept {{
{preamble(used_symbols(mm_defs, [e for _, e in mm_assign]), n)}
{mm_text}
{mirror}
}}

}}  // namespace {ns}
"""

    return dynamics_hpp, (id_m, id_a, mm_m, mm_a)


def parameter_tables(joints, desc, bp, Y, name):
    """What parameters.hpp lists: base-parameter names and groupings, the standard -> base map, each
    base column's rows, the rotor inertias' places, the joints' origins and kinds, the robot id."""
    n = len(joints)
    n_std = 10 * n
    base_names = []
    groupings = []
    for b, k in enumerate(bp.independent):
        terms = [(bp.dependent[d], bp.beta[b, d]) for d in range(len(bp.dependent)) if bp.beta[b, d] != 0.0]
        grouped = bool(terms) or any(any(bi == b for bi, _ in g) for g in bp.rotor_grouping.values())
        base_names.append(std_name(k) + ("_R" if grouped else ""))
        expr = std_name(k) + "".join(f" {'+' if c > 0 else '-'} {abs(c):.12g}*{std_name(d)}" for d, c in terms)
        for j, g in sorted(bp.rotor_grouping.items()):
            for bi, c in g:
                if bi == b:
                    expr += f" {'+' if c > 0 else '-'} {abs(c):.12g}*Ia{j + 1}"
        groupings.append(f"//   {base_names[-1]} = {expr}")
    map_lines = []
    for b, k in enumerate(bp.independent):
        terms = [f" + Scalar({fmt(bp.beta[b, d])}) * phi[{bp.dependent[d]}]" for d in range(len(bp.dependent)) if bp.beta[b, d] != 0.0]
        map_lines.append(f"  phi_b[{b}] = phi[{k}]" + "".join(terms) + ";")
    col_rows = []
    for k in bp.independent:
        rows = [i for i in range(n) if Y[i][k] != 0]
        col_rows.append(f"{{{min(rows)}, {max(rows)}}}" if rows else "{0, -1}")
    rotor_sep = ", ".join("true" if x else "false" for x in bp.rotor_independent)
    absorbed = []
    absorbed_coeff = []
    for j in range(n):
        g = bp.rotor_grouping.get(j, [])
        if len(g) > 1:
            raise RuntimeError(f"rotor inertia of joint {j + 1} spreads over several base parameters")
        absorbed.append(str(g[0][0]) if g else "-1")
        absorbed_coeff.append(f"{fmt(g[0][1])}" if g else "0.0")
    declared_ia = bool(desc.get("rotor_inertia", False))
    origins = []
    for j in joints:
        Rn = [[float(j.R[r, c].evalf()) for c in range(3)] for r in range(3)]
        pn = [float(x) for x in j.p.evalf()]
        origins.append("    {{" + ", ".join(fmt(x) for row in Rn for x in row) + "}, {" + ", ".join(fmt(x) for x in pn) + "}}")
    # A prismatic joint changes what the values mean: it enters the id (a revolute-only arm's id is as before).
    kinds = [f"joint {i + 1} prismatic" for i, j in enumerate(joints) if j.kind == description.PRISMATIC]
    robot_id = fnv1a32("\n".join([name] + groupings + origins + kinds))
    prismatic_list = ", ".join("true" if j.kind == description.PRISMATIC else "false" for j in joints)
    nominal = ", ".join(fmt(x) for j in joints for x in j.standard)
    std_enum = ",\n".join(f"  {std_name(k)} = {k}" for k in range(n_std))
    base_enum = ",\n".join(f"  {nm} = {b}" for b, nm in enumerate(base_names))
    zero_list = ", ".join(std_name(k) for k in bp.zero_columns if k < n_std)
    return types.SimpleNamespace(absorbed=absorbed, absorbed_coeff=absorbed_coeff, base_enum=base_enum, base_names=base_names, col_rows=col_rows, declared_ia=declared_ia, groupings=groupings, kinds=kinds, map_lines=map_lines, nominal=nominal, origins=origins, prismatic_list=prismatic_list, robot_id=robot_id, rotor_sep=rotor_sep, std_enum=std_enum, zero_list=zero_list)


def parameters_header(joints, desc, bp, Y, name, inputs):
    """parameters.hpp: parameter index names, the standard -> base map, kinematic data."""
    n = len(joints)
    n_std = 10 * n
    ns = f"dyncal::generated::{name}"
    nb = len(bp.independent)
    t = parameter_tables(joints, desc, bp, Y, name)
    params_hpp = banner(name, inputs, "parameter index names, standard->base map, kinematic data", {})
    params_hpp += f"""#pragma once

#include <Eigen/Core>
#include <cstdint>

namespace {ns} {{

inline constexpr const char* kRobotName = "{name}";
/// Robot id of parameter tables (dyncal/parameter_table.hpp): FNV-1a 32 of the robot name, the
/// base-parameter groupings and the joint origins, i.e. of what a base-parameter value means.
inline constexpr std::uint32_t kRobotId = 0x{t.robot_id:08x}u;
inline constexpr int kNumJoints = {n};
/// Standard parameters: 10 per link, [XX XY XZ YY YZ ZZ] [kg m^2] about the link frame origin,
/// [MX MY MZ] [kg m], M [kg] (Khalil-Kleinfinger order).
inline constexpr int kNumStandard = {n_std};
/// Base parameters: independent combinations of the standard ones (Gautier 1990).
inline constexpr int kNumBase = {nb};

enum class StandardParam : int {{
{t.std_enum}
}};

inline constexpr const char* kStandardParamNames[kNumStandard] = {{
{", ".join('"' + std_name(k) + '"' for k in range(n_std))}}};

/// Base parameter names: the standard parameter each one is anchored on, with suffix _R where
/// other parameters are regrouped onto it. The groupings (numeric QR, tolerance
/// {base_parameters.RANK_TOLERANCE:g}, {base_parameters.NUM_SAMPLES} random states):
{chr(10).join(t.groupings)}
/// Standard parameters with no effect on the torques: {t.zero_list or "none"}.
enum class BaseParam : int {{
{t.base_enum}
}};

inline constexpr const char* kBaseParamNames[kNumBase] = {{
{", ".join('"' + nm + '"' for nm in t.base_names)}}};

/// Standard index each base parameter is anchored on.
inline constexpr int kBaseAnchor[kNumBase] = {{{", ".join(str(k) for k in bp.independent)}}};

/// Structural sparsity of the base regressor: column b of Y_b can be nonzero only in rows
/// kBaseColumnRows[b][0]..kBaseColumnRows[b][1] (0-based joints; a link's parameters act on its
/// own joint and the joints before it). Rows outside the range are written as exact zeros.
inline constexpr int kBaseColumnRows[kNumBase][2] = {{{", ".join(t.col_rows)}}};

/// Rotor inertia Ia_j (q_dd_j column, reflected to the joint side): true where it is identifiable
/// as a parameter of its own; otherwise it is absorbed into base parameter
/// kRotorInertiaAbsorbedInto[j] with coefficient kRotorInertiaAbsorbedCoefficient[j].
/// Computed only when the description declares rotor inertia ({"yes" if t.declared_ia else "no"}).
inline constexpr bool kRotorInertiaSeparate[kNumJoints] = {{{t.rotor_sep}}};
inline constexpr int kRotorInertiaAbsorbedInto[kNumJoints] = {{{", ".join(t.absorbed)}}};
inline constexpr double kRotorInertiaAbsorbedCoefficient[kNumJoints] = {{{", ".join(t.absorbed_coeff)}}};

/// Joint kinds: true where joint i is prismatic (q [m] along its z axis, tau a force [N]), false
/// where it is revolute (q [rad] about z, tau [Nm]).
inline constexpr bool kJointPrismatic[kNumJoints] = {{{t.prismatic_list}}};

/// Gravity [m/s^2] in the base frame.
inline constexpr double kGravity[3] = {{{", ".join(fmt(g) for g in desc["gravity"])}}};

/// Joint i's fixed transform before its motion along z: rotation (row-major) and offset [m]
/// in the parent frame, T(i-1, i) = [R p] * Rz(q_i), or [R p] * Tz(q_i) where kJointPrismatic[i].
struct JointOrigin {{
  double R[9];
  double p[3];
}};
inline constexpr JointOrigin kJointOrigins[kNumJoints] = {{
{("," + chr(10)).join(t.origins)}}};

/// Nominal standard parameters from the description (CAD / URDF values), StandardParam order.
inline constexpr double kNominalStandard[kNumStandard] = {{{t.nominal}}};

/// Standard -> base parameters: phi_b ({nb}) from phi ({n_std}). Rotor inertia is not included.
template <typename Scalar>
inline void standard_to_base(const Eigen::Matrix<Scalar, {n_std}, 1>& phi, Eigen::Matrix<Scalar, {nb}, 1>& phi_b) noexcept {{
{chr(10).join(t.map_lines)}
}}

}}  // namespace {ns}
"""

    return params_hpp


def robot_header(name, inputs):
    """robot.hpp: the Robot traits type gathering the generated model."""
    ns = f"dyncal::generated::{name}"
    robot_hpp = banner(name, inputs, "the Robot traits type gathering the generated model", {})
    robot_hpp += f"""#pragma once

#include "dynamics.hpp"
#include "dyncal/robot_model.hpp"
#include "parameters.hpp"
#include "regressor.hpp"

namespace {ns} {{

/// The generated {name} model as one type, for templates in lib/: meets dyncal/robot_model.hpp.
struct Robot {{
  static constexpr const char* kName = kRobotName;
  static constexpr std::uint32_t kRobotId = {ns}::kRobotId;
  static constexpr int kNumJoints = {ns}::kNumJoints;
  static constexpr int kNumStandard = {ns}::kNumStandard;
  static constexpr int kNumBase = {ns}::kNumBase;

  template <typename Scalar>
  using JointVector = Eigen::Matrix<Scalar, kNumJoints, 1>;

  /// Whether joint j's (0-based) rotor inertia is a base parameter of its own.
  static constexpr bool rotor_inertia_separate(int j) {{ return kRotorInertiaSeparate[j]; }}
  /// Base parameter that absorbs joint j's rotor inertia when it is not separate (else -1).
  static constexpr int rotor_inertia_absorbed_into(int j) {{ return kRotorInertiaAbsorbedInto[j]; }}
  static constexpr const char* base_param_name(int i) {{ return kBaseParamNames[i]; }}
  /// First and last row (0-based joint) where base column b can be nonzero (kBaseColumnRows).
  static constexpr int base_column_first_row(int b) {{ return kBaseColumnRows[b][0]; }}
  static constexpr int base_column_last_row(int b) {{ return kBaseColumnRows[b][1]; }}
  /// Whether joint j (0-based) is prismatic (q [m], tau [N]) rather than revolute (q [rad], tau [Nm]).
  static constexpr bool joint_prismatic(int j) {{ return kJointPrismatic[j]; }}
  /// Gravity [m/s^2] along base axis i.
  static constexpr double gravity(int i) {{ return kGravity[i]; }}
  static constexpr const char* standard_param_name(int i) {{ return kStandardParamNames[i]; }}

  template <typename Scalar>
  static void standard_regressor(const JointVector<Scalar>& q, const JointVector<Scalar>& qd,
                                 const JointVector<Scalar>& qdd,
                                 Eigen::Matrix<Scalar, kNumJoints, kNumStandard>& Y) noexcept {{
    {ns}::standard_regressor(q, qd, qdd, Y);
  }}
  /// Writes Y_b into the first kNumBase columns of Yb (Cols >= kNumBase; the rest is untouched).
  template <typename Scalar, int Cols>
  static void base_regressor(const JointVector<Scalar>& q, const JointVector<Scalar>& qd,
                             const JointVector<Scalar>& qdd, Eigen::Matrix<Scalar, kNumJoints, Cols>& Yb) noexcept {{
    {ns}::base_regressor(q, qd, qdd, Yb);
  }}
  template <typename Scalar>
  static void inverse_dynamics(const JointVector<Scalar>& q, const JointVector<Scalar>& qd,
                               const JointVector<Scalar>& qdd,
                               const Eigen::Matrix<Scalar, kNumStandard, 1>& phi,
                               JointVector<Scalar>& tau) noexcept {{
    {ns}::inverse_dynamics(q, qd, qdd, phi, tau);
  }}
  template <typename Scalar>
  static void mass_matrix(const JointVector<Scalar>& q, const Eigen::Matrix<Scalar, kNumStandard, 1>& phi,
                          Eigen::Matrix<Scalar, kNumJoints, kNumJoints>& M) noexcept {{
    {ns}::mass_matrix(q, phi, M);
  }}
  template <typename Scalar>
  static void standard_to_base(const Eigen::Matrix<Scalar, kNumStandard, 1>& phi,
                               Eigen::Matrix<Scalar, kNumBase, 1>& phi_b) noexcept {{
    {ns}::standard_to_base(phi, phi_b);
  }}
}};

static_assert(dyncal::is_robot_model_v<Robot>, "the generated {name} model does not meet dyncal/robot_model.hpp");

}}  // namespace {ns}
"""
    return robot_hpp


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    robot_dir, out_dir = sys.argv[1], sys.argv[2]
    t0 = time.time()
    try:
        desc, joints = description.load(robot_dir)
    except description.DescriptionError as e:
        print(f"generate.py: {e}", file=sys.stderr)
        return 2
    name = desc["name"]
    n = len(joints)
    gravity = [sp.Float(g) if g != 0 else sp.Integer(0) for g in desc["gravity"]]
    inputs = input_digest(robot_dir, desc)
    regressor_hpp, bp, Y, (std_m, std_a, base_m, base_a) = regressor_header(joints, desc, gravity, name, inputs)
    nb = len(bp.independent)
    dynamics_hpp, (id_m, id_a, mm_m, mm_a) = dynamics_header(joints, gravity, name, inputs)
    params_hpp = parameters_header(joints, desc, bp, Y, name, inputs)
    robot_hpp = robot_header(name, inputs)
    os.makedirs(out_dir, exist_ok=True)
    for fname, text in (("parameters.hpp", params_hpp), ("regressor.hpp", regressor_hpp),
                        ("dynamics.hpp", dynamics_hpp), ("robot.hpp", robot_hpp)):
        with open(os.path.join(out_dir, fname), "w") as f:
            f.write(text)
    print(f"{name}: {n} joints, {nb} base parameters; Y {std_m}*/{std_a}+, Y_b {base_m}*/{base_a}+, "
          f"ID {id_m}*/{id_a}+, M {mm_m}*/{mm_a}+; {time.time() - t0:.1f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
