"""robot.json validation (docs/robots.md is the schema's reference): one-line errors naming the
field, the same rules as the C++ loader (host_sim/common/src/robot_description.cpp)."""
import math
import os


class SchemaError(Exception):
    pass


def _number(value, field, positive=False):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SchemaError(f"{field}: expected a finite number, got {value!r}")
    if positive and value <= 0:
        raise SchemaError(f"{field}: must be > 0, got {value}")
    return float(value)


def _vector(obj, key, n, field, positive=False, required=True):
    if key not in obj:
        if required:
            raise SchemaError(f"{field}.{key}: missing")
        return None
    v = obj[key]
    if not isinstance(v, list):
        raise SchemaError(f"{field}.{key}: expected a list of {n} numbers")
    if n is not None and len(v) != n:
        raise SchemaError(f"{field}.{key}: {len(v)} entries, expected {n} (one per joint)")
    return [_number(x, f"{field}.{key}[{i + 1}]", positive) for i, x in enumerate(v)]


def _object(obj, key, field, required=True):
    if key not in obj:
        if required:
            raise SchemaError(f"{field}{key}: missing")
        return None
    if not isinstance(obj[key], dict):
        raise SchemaError(f"{field}{key}: expected an object")
    return obj[key]


def _validate_mdh(desc, kin):
    """An mdh description's joints {alpha, a, d, theta[, sigma]} and links; returns the joint count."""
    rows = kin.get("joints")
    if not isinstance(rows, list) or not rows:
        raise SchemaError("kinematics.joints: expected a list of {alpha, a, d, theta}")
    for i, row in enumerate(rows):
        for k in ("alpha", "a", "d", "theta"):
            if not isinstance(row, dict) or k not in row:
                raise SchemaError(f"kinematics.joints[{i + 1}].{k}: missing")
            _number(row[k], f"kinematics.joints[{i + 1}].{k}")
        if "sigma" in row and (isinstance(row["sigma"], bool) or row["sigma"] not in (0, 1)):
            raise SchemaError(f"kinematics.joints[{i + 1}].sigma: expected 0 (revolute) or 1 (prismatic), "
                              f"got {row['sigma']!r}")
    links = desc.get("links")
    if not isinstance(links, list) or len(links) != len(rows):
        raise SchemaError(f"links: expected one entry per joint ({len(rows)}) for an mdh description")
    for i, link in enumerate(links):
        where = f"links[{i + 1}]"
        if not isinstance(link, dict):
            raise SchemaError(f"{where}: expected an object")
        _number(link.get("mass"), where + ".mass")
        _vector(link, "com", 3, where)
        _vector(link, "inertia", 6, where)
    return len(rows)


def _validate_transmission(tr, n):
    """The transmission's gear ratios, joint offsets, torque constants and couplings of n joints."""
    gear = _vector(tr, "gear_ratios", n, "transmission", required=False)  # default 1 (docs/robots.md)
    for i, g in enumerate(gear or []):
        if g == 0:
            raise SchemaError(f"transmission.gear_ratios[{i + 1}]: is 0")
    _vector(tr, "joint_offsets", n, "transmission", required=False)
    kt = _vector(tr, "torque_constants", n, "transmission", required=False)
    for i, k in enumerate(kt or []):
        if k == 0:
            raise SchemaError(f"transmission.torque_constants[{i + 1}]: is 0")
    cs = tr.get("coupling", [])
    if not isinstance(cs, list):
        raise SchemaError("transmission.coupling: expected a list of {motor, joint, ratio}")
    for k, c in enumerate(cs):
        where = f"transmission.coupling[{k + 1}]"
        if not isinstance(c, dict):
            raise SchemaError(f"{where}: expected an object {{motor, joint, ratio}}")
        for key in ("motor", "joint"):
            v = c.get(key)
            if isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= n:
                raise SchemaError(f"{where}.{key}: expected a joint number 1..{n}, got {v!r}")
        if c["motor"] == c["joint"]:
            raise SchemaError(f"{where}: motor and joint are the same (its ratio is gear_ratios)")
        if "ratio" not in c:
            raise SchemaError(f"{where}.ratio: missing")
        _number(c["ratio"], f"{where}.ratio")


def _validate_friction(fr, n):
    """robot.json's friction: one object {Fc, beta, Fs, qds} per joint, or none."""
    if fr is None:
        return
    if not isinstance(fr, list) or len(fr) != n:
        raise SchemaError(f"friction: expected one entry per joint ({n})")
    for i, f in enumerate(fr):
        if not isinstance(f, dict):
            raise SchemaError(f"friction[{i + 1}]: expected an object {{Fc, beta, Fs, qds}}")
        for k in ("Fc", "beta", "Fs", "qds"):
            if k in f:
                _number(f[k], f"friction[{i + 1}].{k}", positive=(k == "qds"))


def validate(desc, robot_dir):
    """Checks the fields the code generator and the tools read. Returns the joint count."""
    if not isinstance(desc, dict):
        raise SchemaError("the file is not a JSON object")
    name = desc.get("name")
    if not isinstance(name, str) or not name or not name.replace("_", "a").isalnum() or not name[0].isalpha():
        raise SchemaError(f"name: expected an identifier (letters, digits, '_'; a letter first), got {name!r}")
    folder = os.path.basename(os.path.normpath(robot_dir))
    if name != folder:
        raise SchemaError(f"name: '{name}' differs from the folder name '{folder}'")
    kin = _object(desc, "kinematics", "")
    fmt = kin.get("format")
    if fmt == "mdh":
        n = _validate_mdh(desc, kin)
    elif fmt == "urdf":
        f = kin.get("file")
        if not isinstance(f, str) or not os.path.isfile(os.path.join(robot_dir, f)):
            raise SchemaError(f"kinematics.file: {f!r} is not a file in {robot_dir}")
        n = None
    else:
        raise SchemaError(f"kinematics.format: expected 'mdh' or 'urdf', got {fmt!r}")
    if "gravity" in desc:
        _vector(desc, "gravity", 3, "")
    types = desc.get("joint_types")
    if types is not None:
        if not isinstance(types, list) or (n is not None and len(types) != n):
            raise SchemaError("joint_types: expected a list of \"revolute\" or \"prismatic\", one per joint")
        for i, t in enumerate(types):
            if t not in ("revolute", "prismatic"):
                raise SchemaError(f"joint_types[{i + 1}]: expected \"revolute\" or \"prismatic\", got {t!r}")
    if "rotor_inertia" in desc and not isinstance(desc["rotor_inertia"], bool):
        raise SchemaError("rotor_inertia: expected true or false")
    lim = _object(desc, "limits", "")
    q_min = _vector(lim, "q_min", n, "limits")
    n = len(q_min)
    if not 1 <= n <= 7:
        raise SchemaError(f"limits.q_min: {n} joints; dyncal takes 1 to 7")
    if types is not None and len(types) != n:
        raise SchemaError(f"joint_types: {len(types)} entries, expected {n} (one per joint)")
    q_max = _vector(lim, "q_max", n, "limits")
    for i in range(n):
        if q_max[i] <= q_min[i]:
            raise SchemaError(f"limits.q_max[{i + 1}]: {q_max[i]} is not above q_min {q_min[i]}")
    _vector(lim, "qd_max", n, "limits", positive=True)
    _vector(lim, "qdd_max", n, "limits", positive=True, required=False)
    _vector(lim, "tau_max", n, "limits", positive=True, required=False)
    tr = _object(desc, "transmission", "", required=False)
    if tr is not None:
        _validate_transmission(tr, n)
    _validate_friction(desc.get("friction"), n)
    return n
