"""Robot descriptions: URDF or modified DH (Khalil-Kleinfinger) -> a chain of revolute and
prismatic joints.

Every joint i is reduced to a fixed transform followed by its motion q_i along its own z axis: a
rotation [rad] for a revolute joint, a translation [m] for a prismatic one (Khalil-Kleinfinger's
sigma_i = 0 or 1):
    T(i-1, i) = [R_fixed  p] * Rz(q_i)   or   [R_fixed  p] * Tz(q_i)
Link i's frame is the frame after that motion. Angles within 1e-9 rad of a multiple of pi/2 are
snapped to the exact value so that the generator folds the resulting zeros and ones.
"""
import json
import math
import os
import xml.etree.ElementTree as ET

import sympy as sp

SNAP_TOLERANCE = 1e-9


class DescriptionError(Exception):
    pass


def exact_angle(value):
    """A float angle [rad] as a SymPy number, exact when it is a multiple of pi/2."""
    quarter = value / (math.pi / 2)
    k = round(quarter)
    if abs(value - k * math.pi / 2) < SNAP_TOLERANCE:
        return sp.Integer(k) * sp.pi / 2
    return sp.Float(value)


def exact_length(value):
    if value == 0.0:
        return sp.Integer(0)
    return sp.Float(value)


def rot_x(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def rpy_matrix(rpy):
    """URDF fixed-axis roll-pitch-yaw: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    return rot_z(exact_angle(rpy[2])) * rot_y(exact_angle(rpy[1])) * rot_x(exact_angle(rpy[0]))


REVOLUTE, PRISMATIC = "revolute", "prismatic"


class Joint:
    """One joint: its kind (REVOLUTE: q turns about z; PRISMATIC: q slides along z), fixed rotation
    R (3x3 SymPy), fixed offset p (3x1, in the parent frame), and the link it carries, as 10 standard
    parameters about the link frame origin."""

    def __init__(self, name, R, p, origin_xyz, origin_rpy, standard, kind=REVOLUTE):
        self.name = name
        self.kind = kind
        self.R = R
        self.p = p
        self.origin_xyz = origin_xyz
        self.origin_rpy = origin_rpy
        self.standard = standard


STANDARD_NAMES = ["XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M"]


def standard_from_com(mass, com, inertia_com, R_com=None):
    """Standard parameters [XX XY XZ YY YZ ZZ MX MY MZ M] about the link origin (link axes) from
    mass [kg], centre of mass [m] and inertia about it [kg m^2] (ixx ixy ixz iyy iyz izz, axes R_com)."""
    import numpy as np

    ixx, ixy, ixz, iyy, iyz, izz = inertia_com
    Ic = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], dtype=float)
    if R_com is not None:
        Rn = np.array(R_com.evalf(), dtype=float)
        Ic = Rn @ Ic @ Rn.T
    c = np.array(com, dtype=float)
    Io = Ic + mass * (c @ c * np.eye(3) - np.outer(c, c))
    return [Io[0, 0], Io[0, 1], Io[0, 2], Io[1, 1], Io[1, 2], Io[2, 2],
            mass * c[0], mass * c[1], mass * c[2], mass]


def load_mdh_kinematics(desc):
    """Joints of a modified-DH description without inertials (standard = None)."""
    return _mdh_joints(desc["kinematics"]["joints"], [None] * len(desc["kinematics"]["joints"]))


def load_mdh(desc):
    links = desc.get("links")
    rows = desc["kinematics"]["joints"]
    if links is None or len(links) != len(rows):
        raise DescriptionError("an mdh description needs one 'links' entry per joint")
    return _mdh_joints(rows, links)


def _mdh_joints(rows, links):
    joints = []
    for i, (row, link) in enumerate(zip(rows, links)):
        alpha = exact_angle(float(row["alpha"]))
        theta = exact_angle(float(row["theta"]))
        a = exact_length(float(row["a"]))
        d = exact_length(float(row["d"]))
        # Rx(alpha) Tx(a) Rz(theta) Tz(d), then Rz(q) (sigma 0) or Tz(q) (sigma 1)
        R = rot_x(alpha) * rot_z(theta)
        p = sp.Matrix([a, 0, 0]) + rot_x(alpha) * sp.Matrix([0, 0, d])
        standard = None if link is None else standard_from_com(float(link["mass"]), link["com"], link["inertia"])
        xyz = [float(v) for v in p.evalf()]
        kind = PRISMATIC if int(row.get("sigma", 0)) == 1 else REVOLUTE
        joints.append(Joint(f"joint_{i + 1}", sp.simplify(R), p, xyz, None, standard, kind))
    return joints


def _floats(text, n):
    vals = [float(v) for v in (text or " ".join(["0"] * n)).split()]
    if len(vals) != n:
        raise DescriptionError(f"expected {n} numbers, got '{text}'")
    return vals


def load_urdf(path):
    root = ET.parse(path).getroot()
    links = {l.get("name"): l for l in root.findall("link")}
    by_parent = {}
    for j in root.findall("joint"):
        by_parent.setdefault(j.find("parent").get("link"), []).append(j)
    children = {j.find("child").get("link") for j in root.findall("joint")}
    roots = [n for n in links if n not in children]
    if len(roots) != 1:
        raise DescriptionError(f"URDF must have one root link, found {roots}")
    joints = []
    current = roots[0]
    while current in by_parent:
        nxt = by_parent[current]
        if len(nxt) != 1:
            raise DescriptionError(f"URDF is not a serial chain at link '{current}'")
        j = nxt[0]
        child = j.find("child").get("link")
        jtype = j.get("type")
        origin = j.find("origin")
        xyz = _floats(origin.get("xyz") if origin is not None else None, 3)
        rpy = _floats(origin.get("rpy") if origin is not None else None, 3)
        inertial = links[child].find("inertial")
        mass = float(inertial.find("mass").get("value")) if inertial is not None else 0.0
        if jtype == "fixed":
            if mass != 0.0:
                raise DescriptionError(f"fixed joint '{j.get('name')}' carries mass; merge it first")
            current = child
            continue
        if jtype not in ("revolute", "continuous", "prismatic"):
            raise DescriptionError(f"joint '{j.get('name')}': only revolute and prismatic joints are supported")
        axis = _floats(j.find("axis").get("xyz") if j.find("axis") is not None else "1 0 0", 3)
        if axis != [0.0, 0.0, 1.0]:
            raise DescriptionError(f"joint '{j.get('name')}': axis must be 0 0 1 (got {axis})")
        R = rpy_matrix(rpy)
        p = sp.Matrix([exact_length(v) for v in xyz])
        if inertial is None:
            standard = [0.0] * 10
        else:
            io = inertial.find("origin")
            cxyz = _floats(io.get("xyz") if io is not None else None, 3)
            crpy = _floats(io.get("rpy") if io is not None else None, 3)
            t = inertial.find("inertia")
            inertia = [float(t.get(k)) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")]
            standard = standard_from_com(mass, cxyz, inertia, rpy_matrix(crpy))
        kind = PRISMATIC if jtype == "prismatic" else REVOLUTE
        joints.append(Joint(j.get("name"), sp.simplify(R), p, xyz, rpy, standard, kind))
        current = child
    return joints


def read_json(path):
    """The JSON object of file `path` (UTF-8). Raises DescriptionError with one line: unreadable, not
    UTF-8, invalid JSON, nested too deeply."""
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except OSError as e:
        raise DescriptionError(f"{path}: cannot be read ({e.strerror})") from None
    except UnicodeDecodeError as e:
        raise DescriptionError(f"{path}: not UTF-8 text (byte {e.start})") from None
    except json.JSONDecodeError as e:
        raise DescriptionError(f"{path}: invalid JSON: {e}") from None
    except RecursionError:
        raise DescriptionError(f"{path}: invalid JSON: nested too deeply") from None


def load(robot_dir):
    """Load robots/<name>/robot.json, validate it (schema.py, docs/robots.md) and load its
    kinematics. Returns (description dict, joints); "gravity" defaults to [0, 0, -9.81].
    Raises DescriptionError with a one-line message naming the file and the field."""
    from dyncal_codegen import schema

    path = os.path.join(robot_dir, "robot.json")
    desc = read_json(path)
    try:
        n = schema.validate(desc, robot_dir)
        joints = load_description(robot_dir, desc)
    except (schema.SchemaError, DescriptionError) as e:
        raise DescriptionError(f"{path}: {e}") from None
    if len(joints) != n:
        raise DescriptionError(f"{path}: limits list {n} joints, the kinematics {len(joints)}")
    kinds = desc.get("joint_types", [REVOLUTE] * n if desc["kinematics"]["format"] == "urdf" else None)
    for i, j in enumerate(joints):
        if kinds is not None and kinds[i] != j.kind:
            raise DescriptionError(f"{path}: joint_types[{i + 1}] is {kinds[i]}, the kinematics' joint {i + 1} "
                                   f"is {j.kind}")
    desc.setdefault("gravity", [0.0, 0.0, -9.81])
    return desc, joints


def check_inertials(joints):
    """Raises DescriptionError naming the first link whose inertial cannot be a link of this arm: a
    value that is not finite, a negative mass, an inertia without mass, or a principal moment about
    the centre of mass above m (2 R)^2, R the arm's extent (sum of the joint offsets and the largest
    centre-of-mass distance): a body inside the arm's reach cannot be spread wider. Returns one
    warning per link whose inertia about the centre of mass no rigid body has (a negative principal
    moment, or I1 + I2 < I3; tolerance 1e-9 of the largest): published parameter sets have them (the
    survey's er20 link 3), and the tools take them as they are (pcls projects its prior onto the
    consistent set)."""
    import numpy as np

    warnings = []
    with_inertials = [j for j in joints if j.standard is not None]
    if not with_inertials:
        return warnings
    extent = sum(float(np.linalg.norm(np.array(j.p.evalf(), dtype=float))) for j in joints)
    for k, j in enumerate(joints):
        if j.standard is None:
            continue
        s = np.array([float(x) for x in j.standard], dtype=float)
        if not np.all(np.isfinite(s)):
            raise DescriptionError(f"link {k + 1}: an inertial value is not finite")
        m = s[9]
        if m < 0:
            raise DescriptionError(f"link {k + 1}: mass {m:g} kg is negative")
        if m > 0:
            extent = max(extent, float(np.linalg.norm(s[6:9] / m)))
    for k, j in enumerate(joints):
        if j.standard is None:
            continue
        s = np.array([float(x) for x in j.standard], dtype=float)
        m = s[9]
        Io = np.array([[s[0], s[1], s[2]], [s[1], s[3], s[4]], [s[2], s[4], s[5]]])
        c = s[6:9] / m if m > 0 else np.zeros(3)
        Ic = Io - m * (c @ c * np.eye(3) - np.outer(c, c))
        if not np.all(np.isfinite(Ic)):
            raise DescriptionError(f"link {k + 1}: the inertia is not finite")
        ev = np.linalg.eigvalsh(Ic)
        tol = 1e-9 * max(1e-12, abs(ev).max())
        if m == 0 and abs(ev).max() > 0:
            raise DescriptionError(f"link {k + 1}: an inertia without mass")
        if extent > 0 and ev[2] > m * (2 * extent) ** 2 * (1 + 1e-9):
            raise DescriptionError(f"link {k + 1}: principal moment {ev[2]:.6g} kg m^2 would need its {m:g} kg "
                                   f"spread beyond {2 * extent:.3g} m, twice the arm's extent")
        if ev[0] < -tol or ev[0] + ev[1] < ev[2] - tol:
            warnings.append(f"link {k + 1}: principal moments {ev[0]:.6g}, {ev[1]:.6g}, {ev[2]:.6g} kg m^2 about the "
                            "centre of mass: no rigid body has them (negative, or I1 + I2 < I3)")
    return warnings


def load_description(robot_dir, desc):
    """Joints of the description's "kinematics" entry (MDH with "links", or a URDF file), their
    inertials checked (check_inertials)."""
    kin = desc["kinematics"]
    if kin["format"] == "mdh":
        joints = load_mdh(desc)
    elif kin["format"] == "urdf":
        joints = load_urdf(os.path.join(robot_dir, kin["file"]))
    else:
        raise DescriptionError(f"unknown kinematics format '{kin['format']}'")
    check_inertials(joints)  # raises on what cannot be a link; its warnings are robot check's
    return joints
