"""Checks an imported chain against the URDF it came from with orocos-kdl (PyKDL), an independent
kinematics and dynamics library: the frames of every moving joint's child link (forward
kinematics) and, when no link off that chain below the first joint carries mass, the joint torques of KDL's recursive
Newton-Euler on the URDF's own chain (fixed joints as KDL fixed segments, axes as given, massive
fixed links past the tip included) against the normalised chain; the fixed base's mass does not
enter joint torques. Tolerance: 1e-9, relative to max(1, |value|)."""
import copy
import math
import random

import numpy as np
import PyKDL as kdl

from .urdf_import import _link_inertial, _path

TOLERANCE = 1e-9


def _frame(T):
    R = T[:3, :3]
    return kdl.Frame(kdl.Rotation(*[float(v) for v in R.reshape(-1)]), kdl.Vector(*[float(v) for v in T[:3, 3]]))


def _inertia(body):
    I = body.inertia
    return kdl.RigidBodyInertia(float(body.mass), kdl.Vector(*[float(v) for v in body.com]),
                                kdl.RotationalInertia(I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]))


def urdf_chain(links, path_joints, rigid=frozenset()):
    """KDL chain of the URDF path as written: each joint a segment, axis in the parent frame; the
    joints named in `rigid` (moving joints past the tip, which import takes at zero position) fixed."""
    chain, moving_segments = kdl.Chain(), []
    for j in path_joints:
        f = _frame(j.origin)
        if j.moves and j.name not in rigid:
            axis = f.M * kdl.Vector(*[float(v) for v in j.axis])
            kind = kdl.Joint.TransAxis if j.type == "prismatic" else kdl.Joint.RotAxis
            joint = kdl.Joint(j.name, f.p, axis, kind)
        else:
            joint = kdl.Joint(j.name, kdl.Joint.Fixed)
        chain.addSegment(kdl.Segment(j.child, joint, f, _inertia(_link_inertial(links[j.child], j.child))))
        if j.moves and j.name not in rigid:
            moving_segments.append(chain.getNrOfSegments())
    return chain, moving_segments


def normalised_chain(chain):
    out = kdl.Chain()
    for j in chain.joints:
        f = _frame(j["T_fixed"])
        kind = kdl.Joint.TransAxis if j["type"] == "prismatic" else kdl.Joint.RotAxis
        joint = kdl.Joint(j["name"], f.p, f.M * kdl.Vector(0, 0, 1), kind)
        out.addSegment(kdl.Segment(j["name"], joint, f, _inertia(j["body"])))
    return out


def _array(values):
    a = kdl.JntArray(len(values))
    for i, v in enumerate(values):
        a[i] = v
    return a


def _first(path_joints):
    return next(j for j in path_joints if j.moves)


def _subtree_links(link, children):
    out = [link]
    for j in children.get(link, []):
        out += _subtree_links(j.child, children)
    return out


def _rigid_subtree(tip, children):
    """The joints below `tip` in depth-first order, each re-expressed as a segment after the previous
    one: a rigid subtree (fixed joints, and moving joints past the tip taken at zero position) is a
    chain of fixed segments whose frames are each relative to the previous segment's, which KDL's
    chain solvers take exactly (a gripper's two fingers are siblings in the URDF)."""
    out = []
    T_prev = np.eye(4)

    def visit(link, T_link):
        nonlocal T_prev
        for j in children.get(link, []):
            T_child = T_link @ j.origin
            segment = copy.copy(j)
            segment.origin = np.linalg.solve(T_prev, T_child)
            out.append(segment)
            T_prev = T_child
            visit(j.child, T_child)

    visit(tip, np.eye(4))
    return out


def _urdf_path(links, joints, chain):
    """The URDF's joints from the chain's base to its tip, extended past the tip through every link
    below it (_rigid_subtree: a flange, a tool, a gripper's fingers); whether any link off that path
    below the first moving joint carries mass (then the chain alone is not the URDF's dynamics), and
    the moving joints past the tip (import takes them rigid at zero position: so does the check)."""
    children, parent_joint = {}, {}
    for j in joints:
        children.setdefault(j.parent, []).append(j)
        parent_joint[j.child] = j
    path_joints = _path(chain.base, chain.tip, parent_joint, children)
    past_tip = len(path_joints)
    path_joints += _rigid_subtree(chain.tip, children)
    moving_body = {j.child for j in path_joints[path_joints.index(_first(path_joints)):]}
    below = _subtree_links(_first(path_joints).child, children)
    off_path_mass = any(_link_inertial(links[name], name).mass > 0 for name in below if name not in moving_body)
    rigid = frozenset(j.name for j in path_joints[past_tip:] if j.moves)
    return path_joints, off_path_mass, rigid


def check(links, joints, chain, gravity, trials=20, seed=1):
    """Returns (max frame error, max torque error or None when the ID check does not apply)."""
    path_joints, off_path_mass, rigid = _urdf_path(links, joints, chain)
    original, moving_segments = urdf_chain(links, path_joints, rigid)
    normalised = normalised_chain(chain)
    n = len(chain.joints)
    fk_o, fk_n = kdl.ChainFkSolverPos_recursive(original), kdl.ChainFkSolverPos_recursive(normalised)
    g = kdl.Vector(*gravity)
    id_o, id_n = kdl.ChainIdSolver_RNE(original, g), kdl.ChainIdSolver_RNE(normalised, g)
    rng = random.Random(seed)
    frame_error, torque_error = 0.0, 0.0
    for _ in range(trials):
        q = _array([rng.uniform(-math.pi, math.pi) for _ in range(n)])
        qd = _array([rng.uniform(-2, 2) for _ in range(n)])
        qdd = _array([rng.uniform(-5, 5) for _ in range(n)])
        for i in range(n):
            fo, fn = kdl.Frame(), kdl.Frame()
            fk_o.JntToCart(q, fo, moving_segments[i])
            fk_n.JntToCart(q, fn, i + 1)
            A = chain.joints[i]["A"]
            expected = np.array([[fo.M[r, c] for c in range(3)] for r in range(3)]) @ A
            got = np.array([[fn.M[r, c] for c in range(3)] for r in range(3)])
            dp = max(abs(fo.p[k] - fn.p[k]) / max(1.0, abs(fo.p[k])) for k in range(3))
            frame_error = max(frame_error, float(np.max(np.abs(expected - got))), dp)
        if off_path_mass:
            continue
        to, tn = kdl.JntArray(n), kdl.JntArray(n)
        wo = [kdl.Wrench() for _ in range(original.getNrOfSegments())]
        wn = [kdl.Wrench() for _ in range(n)]
        id_o.CartToJnt(q, qd, qdd, wo, to)
        id_n.CartToJnt(q, qd, qdd, wn, tn)
        for i in range(n):
            torque_error = max(torque_error, abs(to[i] - tn[i]) / max(1.0, abs(to[i])))
    return frame_error, (None if off_path_mass else torque_error)


def torques_at(links, joints, chain, gravity, states):
    """KDL's recursive Newton-Euler on the URDF's own chain (as check() builds it) at `states`
    ({"q", "qd", "qdd"}, joint order of `chain`): the torque lists, or None when mass hangs off the
    chain below the first joint (then the chain alone is not the URDF's dynamics)."""
    path_joints, off_path_mass, rigid = _urdf_path(links, joints, chain)
    if off_path_mass:
        return None
    original, _ = urdf_chain(links, path_joints, rigid)
    solver = kdl.ChainIdSolver_RNE(original, kdl.Vector(*gravity))
    n = len(chain.joints)
    out = []
    for s in states:
        tau = kdl.JntArray(n)
        solver.CartToJnt(_array(s["q"]), _array(s["qd"]), _array(s["qdd"]),
                         [kdl.Wrench() for _ in range(original.getNrOfSegments())], tau)
        out.append([tau[i] for i in range(n)])
    return out


def torque_samples(links, joints, chain, gravity, count=200, seed=7):
    """torques_at `count` seeded random states: a list of {"q", "qd", "qdd", "tau"} (rad, rad/s,
    rad/s^2, Nm; m, m/s, m/s^2, N for a prismatic joint), or None (torques_at). The oracle `dyncal
    robot check` runs the compiled model against."""
    n = len(chain.joints)
    rng = random.Random(seed)
    states = []
    for _ in range(count):
        states.append({"q": [rng.uniform(-math.pi, math.pi) for _ in range(n)],
                       "qd": [rng.uniform(-2, 2) for _ in range(n)],
                       "qdd": [rng.uniform(-5, 5) for _ in range(n)]})
    taus = torques_at(links, joints, chain, gravity, states)
    if taus is None:
        return None
    for s, tau in zip(states, taus):
        s["tau"] = tau
    return states
