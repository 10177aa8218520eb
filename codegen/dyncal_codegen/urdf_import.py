"""A stock URDF -> dyncal's normalised serial chain (docs/robots.md, "Importing a URDF").

The normalised chain is what the code generator reads: one joint per moving URDF joint, each a
fixed transform [R p] followed by a rotation q about (revolute, continuous) or a translation q along
(prismatic) its own +z axis, and one rigid body per joint (the URDF links it carries, lumped). From a stock URDF:
- fixed joints are merged: a link attached by fixed joints (a flange, a tool0 frame, a sensor) is
  lumped into the body of the moving joint before it, its inertial included; the links before the
  first moving joint form the fixed base, whose mass does not enter the dynamics;
- any joint axis is handled by re-expressing the joint's child frame: with A a rotation taking +z to
  the axis, Rot(axis, q) = A Rz(q) A^T, so the new frame F' = F A turns about its own +z (A is an
  exact quarter or half turn for +-x, +-y, -z); likewise Trans(axis, q) = A Tz(q) A^T;
- revolute, continuous and prismatic joints are accepted; planar and floating joints, mimic joints
  and a tree whose moving joints branch are refused with one line naming the joint or link.
Errors are ImportError_ with a one-line message.
"""
import math
import xml.etree.ElementTree as ET

import numpy as np

AXIS_TOLERANCE = 1e-12


class ImportError_(Exception):
    pass


def rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def rpy_matrix(rpy):
    """URDF fixed-axis roll-pitch-yaw: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    return rot_z(rpy[2]) @ rot_y(rpy[1]) @ rot_x(rpy[0])


def rpy_from_matrix(R):
    """URDF roll-pitch-yaw with R = Rz(yaw) Ry(pitch) Rx(roll)."""
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if abs(math.cos(pitch)) > 1e-12:
        roll = math.atan2(R[2, 1], R[2, 2])
        yaw = math.atan2(R[1, 0], R[0, 0])
    else:
        roll = math.atan2(-R[1, 2], R[1, 1])
        yaw = 0.0
    return [0.0 if abs(v) < 1e-15 else v for v in (roll, pitch, yaw)]


def transform(R, p):
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p
    return T


def axis_frame(axis):
    """A rotation A with A e_z = axis: exact for the six signed unit axes, Rodrigues otherwise."""
    exact = {(0, 0, 1): np.eye(3), (0, 0, -1): rot_x(math.pi), (1, 0, 0): rot_y(math.pi / 2),
             (-1, 0, 0): rot_y(-math.pi / 2), (0, 1, 0): rot_x(-math.pi / 2), (0, -1, 0): rot_x(math.pi / 2)}
    for key, A in exact.items():
        if np.max(np.abs(axis - np.array(key, dtype=float))) < AXIS_TOLERANCE:
            return np.round(A, 15) + 0.0  # exact zeros and ones where they belong
    k = np.cross([0.0, 0.0, 1.0], axis)
    s, c = np.linalg.norm(k), axis[2]
    k = k / s
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * K + (1 - c) * K @ K


def _floats(element, attribute, n, where, default=None):
    text = element.get(attribute) if element is not None else None
    if text is None:
        if default is None:
            raise ImportError_(f"{where}: missing attribute '{attribute}'")
        return list(default)
    try:
        values = [float(v) for v in text.split()]
    except ValueError:
        raise ImportError_(f"{where}: '{attribute}' is not {n} numbers: '{text}'") from None
    if len(values) != n or not all(math.isfinite(v) for v in values):
        raise ImportError_(f"{where}: '{attribute}' is not {n} finite numbers: '{text}'")
    return values


def _origin(element, where):
    o = element.find("origin")
    xyz = _floats(o, "xyz", 3, where + " <origin>", [0, 0, 0])
    rpy = _floats(o, "rpy", 3, where + " <origin>", [0, 0, 0])
    return transform(rpy_matrix(rpy), xyz)


class Inertial:
    """Mass [kg], centre of mass c [m] and inertia about it I [kg m^2], in some frame."""

    def __init__(self, mass=0.0, com=None, inertia=None):
        self.mass = mass
        self.com = np.zeros(3) if com is None else np.asarray(com, dtype=float)
        self.inertia = np.zeros((3, 3)) if inertia is None else np.asarray(inertia, dtype=float)

    def moved(self, T):
        """The same body expressed in the frame in which T maps this frame's coordinates."""
        R = T[:3, :3]
        return Inertial(self.mass, R @ self.com + T[:3, 3], R @ self.inertia @ R.T)

    def plus(self, other):
        m = self.mass + other.mass
        if m == 0.0:
            return Inertial()
        c = (self.mass * self.com + other.mass * other.com) / m
        inertia = np.zeros((3, 3))
        for b in (self, other):
            d = b.com - c
            inertia += b.inertia + b.mass * (d @ d * np.eye(3) - np.outer(d, d))
        return Inertial(m, c, inertia)


def _link_inertial(link, where):
    el = link.find("inertial")
    if el is None:
        return Inertial()
    m_el = el.find("mass")
    mass = _floats(m_el, "value", 1, where + " <mass>")[0]
    if mass < 0:
        raise ImportError_(f"{where}: negative mass {mass}")
    t = el.find("inertia")
    if t is None:
        raise ImportError_(f"{where}: <inertial> without <inertia>")
    vals = {k: _floats(t, k, 1, where + " <inertia>", [0.0])[0] for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    I_c = np.array([[vals["ixx"], vals["ixy"], vals["ixz"]], [vals["ixy"], vals["iyy"], vals["iyz"]],
                    [vals["ixz"], vals["iyz"], vals["izz"]]])
    T = _origin(el, where + " <inertial>")
    return Inertial(mass, np.zeros(3), I_c).moved(T)


class UrdfJoint:
    def __init__(self, el):
        self.name = el.get("name") or "?"
        where = f"joint '{self.name}'"
        self.type = el.get("type")
        parent, child = el.find("parent"), el.find("child")
        if parent is None or child is None or parent.get("link") is None or child.get("link") is None:
            raise ImportError_(f"{where}: needs <parent link=...> and <child link=...>")
        self.parent, self.child = parent.get("link"), child.get("link")
        self.origin = _origin(el, where)
        self.mimic = el.find("mimic") is not None
        axis = np.array(_floats(el.find("axis"), "xyz", 3, where + " <axis>", [1, 0, 0]))
        norm = np.linalg.norm(axis)
        if self.type in ("revolute", "continuous", "prismatic") and norm < 1e-9:
            raise ImportError_(f"{where}: zero axis")
        self.axis = axis / norm if norm > 0 else axis
        lim = el.find("limit")
        self.limit = {}
        if lim is not None:
            for k in ("lower", "upper", "velocity", "effort"):
                if lim.get(k) is not None:
                    self.limit[k] = _floats(lim, k, 1, where + " <limit>")[0]

    @property
    def moves(self):
        return self.type != "fixed"


class Chain:
    """The normalised chain: per moving joint its URDF name, fixed transform T (4x4, from the
    previous normalised frame), axis frame A, limits, and the lumped body in the new frame."""

    def __init__(self):
        self.joints = []  # dicts: name, T_fixed, A, limit, body (Inertial), type
        self.base = None
        self.tip = None
        self.notes = []  # what import decided that the user should know (joints past the tip)


def parse(path):
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError) as e:
        raise ImportError_(f"{path}: not a readable URDF ({e})") from None
    if root.tag != "robot":
        raise ImportError_(f"{path}: the root element is <{root.tag}>, not <robot>")
    links = {}
    for link in root.findall("link"):
        name = link.get("name")
        if not name:
            raise ImportError_(f"{path}: a <link> without a name")
        links[name] = link
    joints = [UrdfJoint(j) for j in root.findall("joint")]
    for j in joints:
        for end in (j.parent, j.child):
            if end not in links:
                raise ImportError_(f"joint '{j.name}': link '{end}' is not defined")
    return root.get("name") or "robot", links, joints


def _descendant_moving(link, children):
    """The moving joints anywhere below `link`."""
    out = []
    for j in children.get(link, []):
        if j.moves:
            out.append(j)
        out += _descendant_moving(j.child, children)
    return out


def _lump_subtree(link, T_body_link, children, links, skip, past_tip=None):
    """Inertial of `link` and its fixed-only subtree (except the child `skip`), in the body frame.
    past_tip: a list when `link` is the chain's tip: a moving joint below it (a gripper's fingers) is
    then taken at its zero position, rigid, and named in the list; elsewhere a moving joint off the
    chain is refused (a branch whose motion would move the chain's loads)."""
    total = _link_inertial(links[link], f"link '{link}'").moved(T_body_link)
    for j in children.get(link, []):
        if j.child == skip:
            continue
        moving = [j] if j.moves else []
        moving += _descendant_moving(j.child, children)
        if moving and past_tip is None:
            raise ImportError_(f"joint '{moving[0].name}' moves but is not on the chain; choose the chain with --tip")
        if j.moves:
            past_tip.append(j.name)
        total = total.plus(_lump_subtree(j.child, T_body_link @ j.origin, children, links, None, past_tip))
    return total


def _path(base, tip, parent_joint, children):
    """Joints from base to tip: the given tip, or the one chain of moving joints below the base."""
    if tip is not None:
        path, link = [], tip
        while link != base:
            if link not in parent_joint:
                raise ImportError_(f"link '{tip}' is not below the base link '{base}'")
            j = parent_joint[link]
            path.append(j)
            link = j.parent
        return path[::-1]
    path, link = [], base
    while True:
        nxt = [j for j in children.get(link, []) if j.moves or _descendant_moving(j.child, children)]
        if len(nxt) > 1:
            names = " and ".join(f"'{_first_moving(j, children).name}'" for j in nxt[:2])
            raise ImportError_(f"the tree branches at link '{link}': joints {names} both move; choose the chain with --tip")
        if not nxt:
            return path
        path.append(nxt[0])
        link = nxt[0].child


def _first_moving(j, children):
    return j if j.moves else _descendant_moving(j.child, children)[0]


def normalise(path, base=None, tip=None):
    """Reads the URDF at `path` and returns (robot name, Chain). Raises ImportError_."""
    robot_name, links, joints = parse(path)
    children, parent_joint = {}, {}
    for j in joints:
        if j.child in parent_joint:
            raise ImportError_(f"link '{j.child}' has two parent joints ('{parent_joint[j.child].name}', '{j.name}')")
        children.setdefault(j.parent, []).append(j)
        parent_joint[j.child] = j
    if base is None:
        roots = [n for n in links if n not in parent_joint]
        if len(roots) != 1:
            raise ImportError_(f"the URDF has {len(roots)} root links ({', '.join(roots)}); choose one with --base")
        base = roots[0]
    for name, what in ((base, "--base"), (tip, "--tip")):
        if name is not None and name not in links:
            raise ImportError_(f"{what} link '{name}' is not in the URDF")
    path_joints = _path(base, tip, parent_joint, children)
    for j in path_joints:
        if j.type not in ("revolute", "continuous", "prismatic", "fixed"):
            raise ImportError_(f"joint '{j.name}' is {j.type}: dyncal models revolute, continuous and prismatic "
                               "joints only")
        if j.mimic:
            raise ImportError_(f"joint '{j.name}' is a mimic joint: dyncal models independent joints only")
    moving = [j for j in path_joints if j.moves]
    if not 1 <= len(moving) <= 7:
        raise ImportError_(f"the chain from '{base}' has {len(moving)} moving joints; dyncal takes 1 to 7")

    chain = Chain()
    chain.base, chain.tip = base, path_joints[-1].child if path_joints else base
    # Walk the path: T accumulates the fixed transform from the current normalised frame.
    T_acc = np.eye(4)
    A_prev = np.eye(3)
    body = None
    link = base
    for j in path_joints:
        nxt_on_path = j.child
        # lump `link` (and its fixed side subtrees) into the current body
        if body is not None:
            body["body"] = body["body"].plus(_lump_subtree(link, body["T_link"], children, links, nxt_on_path))
        T_acc = T_acc @ j.origin
        if j.moves:
            A = axis_frame(j.axis)
            T_fixed = transform(A_prev.T, np.zeros(3)) @ T_acc @ transform(A, np.zeros(3))
            body = {"name": j.name, "type": j.type, "T_fixed": T_fixed, "A": A, "limit": j.limit,
                    "body": Inertial(), "T_link": transform(A.T, np.zeros(3))}
            chain.joints.append(body)
            T_acc, A_prev = np.eye(4), A
        elif body is not None:
            body["T_link"] = body["T_link"] @ j.origin
        link = nxt_on_path
    past_tip = []
    body["body"] = body["body"].plus(_lump_subtree(link, body["T_link"], children, links, None, past_tip))
    if past_tip:
        chain.notes.append(f"{len(past_tip)} joint{'s' if len(past_tip) > 1 else ''} past the tip '{chain.tip}' "
                           f"({', '.join(past_tip)}) taken rigid at zero position: their links' mass is in the last "
                           "body, their motion is not modelled")
    return robot_name, chain
