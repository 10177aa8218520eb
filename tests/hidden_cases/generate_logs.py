#!/usr/bin/env python3
"""Hidden-case logs for `dyncal diagnose` (issue 22): simulated logs of an arm given only as a URDF,
each with at most one effect the declared model (rigid body + Coulomb + viscous, survey Eq. 7) lacks.

Independent of dyncal's simulated drive and code generator: the URDF is parsed here, the joint
torques are orocos-kdl's recursive Newton-Euler (PyKDL) on the URDF's own chain. A log is
  tau = RNEA(q, qd, qdd) + Fc sgn(qd) + Fv qd + effect + noise,
with sgn(0) = 0 at rest, q read by 20-bit encoders, torque noise of 0.5 % of each joint's torque
range, on a random Fourier excitation (Eq. 27: 5 harmonics of 0.1 Hz inside 80 % of the URDF's
position, velocity limits), played with or without rests (starting and stopping between samples).
The effect's size is set by the part the declared model cannot explain: its columns less their
projection on the joint's own Coulomb and viscous columns have an RMS of kappa noise standard
deviations, kappa uniform in [3, 8] (--kappa).

Every trajectory also gets one coupled-motor case (EXTRA_KINDS) from its own random stream. Every
log has a clean twin (same trajectory, friction and noise, no effect). The manifest
(cases.json) gives the truth of every log: kind, 1-based joints, shape (Stribeck velocity scale,
cycles per revolution, coupling ratio) and coefficients.
"""
import argparse
import json
import math
import os
import xml.etree.ElementTree as ET

import numpy as np
import PyKDL as kdl

ENCODER_STEP = 2 * math.pi / (1 << 20)
GRAVITY = (0.0, 0.0, -9.81)  # URDF convention: z up in the root link's frame
KINDS = ["stribeck", "asymmetric_friction", "velocity_power", "load_friction", "rotor_inertia", "offset",
         "position_periodic", "coupling", "drift"]
# One more case per trajectory, after the others and from its own random stream (the cases above
# stay as they were): a coupled motor, joint j's own motor turning with q_j + r q_i in place of q_j.
EXTRA_KINDS = ["coupled_motor"]


# --- URDF ---------------------------------------------------------------------------------------

def _floats(text, default):
    return [float(v) for v in text.split()] if text else list(default)


def _rpy(r, p, y):
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _origin(element):
    o = element.find("origin") if element is not None else None
    xyz = _floats(o.get("xyz") if o is not None else None, (0, 0, 0))
    rpy = _floats(o.get("rpy") if o is not None else None, (0, 0, 0))
    return _rpy(*rpy), np.array(xyz)


def _frame(R, p):
    return kdl.Frame(kdl.Rotation(*[float(v) for v in R.reshape(-1)]), kdl.Vector(*[float(v) for v in p]))


def _inertia(link):
    inertial = link.find("inertial")
    if inertial is None:
        return kdl.RigidBodyInertia(), 0.0
    R, com = _origin(inertial)
    m = float(inertial.find("mass").get("value"))
    i = inertial.find("inertia")
    g = lambda k: float(i.get(k, "0"))
    Ic = R @ np.array([[g("ixx"), g("ixy"), g("ixz")], [g("ixy"), g("iyy"), g("iyz")],
                       [g("ixz"), g("iyz"), g("izz")]]) @ R.T
    return kdl.RigidBodyInertia(m, kdl.Vector(*com), kdl.RotationalInertia(
        Ic[0, 0], Ic[1, 1], Ic[2, 2], Ic[0, 1], Ic[0, 2], Ic[1, 2])), m


class Arm:
    """The URDF's serial chain from its root link: every joint whose subtree moves or carries mass
    (a massless tool frame or camera is left out; two such branches at one link are refused)."""

    def __init__(self, path):
        root = ET.parse(path).getroot()
        links = {l.get("name"): l for l in root.findall("link")}
        joints = root.findall("joint")
        children = {}
        for j in joints:
            children.setdefault(j.find("parent").get("link"), []).append(j)
        child_links = {j.find("child").get("link") for j in joints}
        (base,) = [name for name in links if name not in child_links]

        def matters(link):
            if _inertia(links[link])[1] > 0:
                return True
            return any(j.get("type") != "fixed" or matters(j.find("child").get("link"))
                       for j in children.get(link, []))

        self.chain, self.lower, self.upper, self.qd_max, self.axes = kdl.Chain(), [], [], [], []
        link = base
        while True:
            nexts = [j for j in children.get(link, []) if j.get("type") != "fixed" or matters(j.find("child").get("link"))]
            if not nexts:
                break
            if len(nexts) > 1:
                raise SystemExit(f"{path}: link '{link}' branches; the generator takes serial chains")
            j = nexts[0]
            R, p = _origin(j)
            f = _frame(R, p)
            child = j.find("child").get("link")
            if j.get("type") in ("revolute", "continuous"):
                axis = R @ np.array(_floats(j.find("axis").get("xyz") if j.find("axis") is not None else None, (1, 0, 0)))
                joint = kdl.Joint(j.get("name"), f.p, kdl.Vector(*axis), kdl.Joint.RotAxis)
                lim = j.find("limit")
                self.lower.append(float(lim.get("lower", -math.pi)))
                self.upper.append(float(lim.get("upper", math.pi)))
                self.qd_max.append(float(lim.get("velocity")))
            elif j.get("type") == "fixed":
                joint = kdl.Joint(j.get("name"), kdl.Joint.Fixed)
            else:
                raise SystemExit(f"{path}: joint '{j.get('name')}' is {j.get('type')}; the generator takes revolute joints")
            self.chain.addSegment(kdl.Segment(child, joint, f, _inertia(links[child])[0]))
            link = child
        self.n = self.chain.getNrOfJoints()
        self.solver = kdl.ChainIdSolver_RNE(self.chain, kdl.Vector(*GRAVITY))
        self.jacobian = kdl.ChainJntToJacSolver(self.chain)

    def torque(self, q, qd, qdd):
        """Joint torques [Nm] of the rigid body, (S, n) arrays in, (S, n) out."""
        n, out = self.n, np.zeros_like(q)
        aq, aqd, aqdd, tau = kdl.JntArray(n), kdl.JntArray(n), kdl.JntArray(n), kdl.JntArray(n)
        wrenches = [kdl.Wrench() for _ in range(self.chain.getNrOfSegments())]
        for k in range(q.shape[0]):
            for i in range(n):
                aq[i], aqd[i], aqdd[i] = q[k, i], qd[k, i], qdd[k, i]
            if self.solver.CartToJnt(aq, aqd, aqdd, wrenches, tau) < 0:
                raise SystemExit("KDL's RNEA failed")
            out[k] = [tau[i] for i in range(n)]
        return out

    def axes_at_home(self):
        """Joint axes in the base frame at q = 0 (the Jacobian's angular rows)."""
        jac = kdl.Jacobian(self.n)
        self.jacobian.JntToJac(kdl.JntArray(self.n), jac)
        return np.array([[jac[r, i] for r in range(3, 6)] for i in range(self.n)])


# --- Trajectory ----------------------------------------------------------------------------------

def fourier_excitation(arm, rng, period=10.0, harmonics=5, fill=0.8):
    """Random Eq. 27 series per joint, scaled into `fill` of the position and velocity limits
    (acceleration at most 4 qd_max per second); returns q(u), qd(u), qdd(u) as a function."""
    w = 2 * math.pi / period
    grid = np.linspace(0, period, 2001)
    coef = []
    for i in range(arm.n):
        a = rng.normal(size=harmonics) / np.arange(1, harmonics + 1)
        b = rng.normal(size=harmonics) / np.arange(1, harmonics + 1)
        q, qd, qdd = _series(a, b, w, grid)
        half = 0.5 * (arm.upper[i] - arm.lower[i])
        s = min(fill * half / np.abs(q).max(), fill * arm.qd_max[i] / np.abs(qd).max(),
                fill * 4 * arm.qd_max[i] / np.abs(qdd).max())
        room = fill * half - s * np.abs(q).max()
        centre = 0.5 * (arm.upper[i] + arm.lower[i]) + rng.uniform(-1, 1) * room
        coef.append((s * a, s * b, centre))

    def evaluate(u):
        out = [_series(a, b, w, u) for a, b, _ in coef]
        q = np.stack([o[0] + c[2] for o, c in zip(out, coef)], axis=1)
        return q, np.stack([o[1] for o in out], axis=1), np.stack([o[2] for o in out], axis=1)
    return evaluate


def _series(a, b, w, t):
    q, qd, qdd = np.zeros_like(t), np.zeros_like(t), np.zeros_like(t)
    for l in range(1, len(a) + 1):
        s, c = np.sin(w * l * t), np.cos(w * l * t)
        q += a[l - 1] / (w * l) * s - b[l - 1] / (w * l) * c
        qd += a[l - 1] * c + b[l - 1] * s
        qdd += -a[l - 1] * w * l * s + b[l - 1] * w * l * c
    return q, qd, qdd


def motion_clock(t, rests, move=3.0, rest=1.5, ramp=0.4):
    """Clock u(t) of the trajectory: u = t, or with rests played `move` s, held `rest` s, with ramps
    of the clock speed w = du/dt; returns u, w, dw/dt (u by trapezoids on a 16x finer grid, u(t[0]) = 0)."""
    if not rests:
        return t - t[0], np.ones_like(t), np.zeros_like(t)

    def speed(x):
        x = np.mod(x, move + rest)
        w = np.where(x < move - ramp, 1.0, np.where(x < move, (move - x) / ramp,
                     np.where(x < move + rest - ramp, 0.0, (x - (move + rest - ramp)) / ramp)))
        wd = np.where(x < move - ramp, 0.0, np.where(x < move, -1 / ramp,
                      np.where(x < move + rest - ramp, 0.0, 1 / ramp)))
        return w, wd

    fine = np.linspace(t[0], t[-1], 16 * (len(t) - 1) + 1)
    wf, _ = speed(fine)
    u = np.concatenate([[0.0], np.cumsum(0.5 * (wf[1:] + wf[:-1]) * np.diff(fine))])[::16]
    w, wd = speed(t)
    return u, w, wd


# --- Effects -------------------------------------------------------------------------------------

def _sgn(x):
    return np.sign(x)


def effect_columns(kind, joints, shape, m):
    """Unit-coefficient torque columns (S, n) of an effect, with a random mix of its parts.
    m: dict of t, q, qd, qdd, tau_rb, rng."""
    S, n = m["q"].shape
    out = np.zeros((S, n))
    j = joints[0] - 1
    qd, rng = m["qd"][:, j], m["rng"]
    top = np.abs(qd).max()
    if kind == "stribeck":
        out[:, j] = _sgn(qd) * np.exp(-(qd / shape) ** 2)
    elif kind == "asymmetric_friction":
        alpha = rng.uniform(0.3, 0.7)
        out[:, j] = alpha * (qd > 0) + (1 - alpha) * qd * (qd > 0) / top
    elif kind == "velocity_power":
        out[:, j] = _sgn(qd) * np.abs(qd / top) ** (1 / 3)
    elif kind == "load_friction":
        out[:, j] = np.abs(m["tau_rb"][:, j]) * _sgn(qd)
    elif kind == "rotor_inertia":
        out[:, j] = m["qdd"][:, j]
    elif kind == "offset":
        out[:, j] = 1.0
    elif kind == "position_periodic":
        out[:, j] = np.sin(shape * m["q"][:, j] + rng.uniform(0, 2 * math.pi))
    elif kind == "coupling":
        i2 = joints[1] - 1
        v = qd + shape * m["qd"][:, i2]
        a = m["qdd"][:, j] + shape * m["qdd"][:, i2]
        mix = rng.dirichlet([2, 2, 1])
        motor = mix[0] * _sgn(v) + mix[1] * v / np.abs(v).max() + mix[2] * a / np.abs(a).max()
        out[:, j], out[:, i2] = motor, shape * motor
    elif kind == "coupled_motor":
        # Joint j's own motor turns with qd_j + r qd_i2 instead of qd_j: its Coulomb and viscous
        # friction (the joint's own values) at that velocity, on joint j and r times on joint i2.
        # The column is the motor's friction only: generate() takes the joint's own friction out.
        i2 = joints[1] - 1
        v = qd + shape * m["qd"][:, i2]
        motor = m["Fc"][j] * _sgn(v) + m["Fv"][j] * v
        out[:, j], out[:, i2] = motor, shape * motor
    elif kind == "drift":
        out[:, j] = (m["t"] - m["t"][0]) / (m["t"][-1] - m["t"][0]) * qd / top
    else:
        raise ValueError(kind)
    return out


def unexplained(col, qd, sigma):
    """The columns less their projection on each joint's own Coulomb and viscous columns, in noise
    standard deviations: sqrt(sum over joints of mean(r_j^2) / sigma_j^2)."""
    total = 0.0
    for j in range(col.shape[1]):
        if not np.any(col[:, j]):
            continue
        A = np.stack([_sgn(qd[:, j]), qd[:, j]], axis=1)
        r = col[:, j] - A @ np.linalg.lstsq(A, col[:, j], rcond=None)[0]
        total += np.mean(r ** 2) / sigma[j] ** 2
    return math.sqrt(total)


def separable_rotor_joints(arm):
    """Joints (0-based) whose rotor inertia is not absorbed into the link inertias: not joint 1,
    and not a joint parallel to every joint before it (Gautier's grouping of Ia_j with ZZ_j)."""
    axes = arm.axes_at_home()
    out = []
    for j in range(1, arm.n):
        if any(np.linalg.norm(np.cross(axes[j], axes[i])) > 1e-6 for i in range(j)):
            out.append(j)
    return out


def draw_effect(kind, arm, rng, m):
    """A kind's joints (1-based) and shape, drawn on any joint the kind applies to."""
    n = arm.n
    if kind == "rotor_inertia":
        return [int(rng.choice(separable_rotor_joints(arm))) + 1], 0.0
    if kind in ("coupling", "coupled_motor"):
        i = int(rng.integers(0, n - 1))
        pair = [i + 1, i + 2] if rng.uniform() < 0.5 else [i + 2, i + 1]
        ratio = math.exp(rng.uniform(math.log(0.2), math.log(3.0))) * (1 if rng.uniform() < 0.7 else -1)
        return pair, ratio
    j = int(rng.integers(0, n))
    if kind == "stribeck":
        return [j + 1], rng.uniform(0.05, 0.15) * np.abs(m["qd"][:, j]).max()
    if kind == "position_periodic":
        return [j + 1], float(rng.integers(2, 25))
    return [j + 1], 0.0


# --- Logs ----------------------------------------------------------------------------------------

def simulate(arm, traj_seed, rests, fs, seconds):
    """The clean log's motion, rigid-body torque, friction and noise for one trajectory."""
    rng = np.random.default_rng(traj_seed)
    evaluate = fourier_excitation(arm, rng)
    t = np.arange(int(round(fs * seconds))) / fs
    # The motion's starts and stops fall between samples (half a period off the logger's grid): a
    # torque step on a sample instant, taking its later value there, would sit half a period before
    # the kink q shows, a timing error at every start and stop (on arm3 with rests, 10x the
    # residual of a clean log).
    u, w, wd = motion_clock(t + 0.5 / fs, rests)
    q, qd_u, qdd_u = evaluate(u)
    qd = w[:, None] * qd_u
    qdd = (w ** 2)[:, None] * qdd_u + wd[:, None] * qd_u
    tau_rb = arm.torque(q, qd, qdd)
    span = tau_rb.max(axis=0) - tau_rb.min(axis=0)
    Fc = rng.uniform(0.02, 0.05, arm.n) * span
    Fv = rng.uniform(0.02, 0.05, arm.n) * span / np.abs(qd).max(axis=0)
    tau = tau_rb + Fc * _sgn(qd) + Fv * qd
    sigma = 0.005 * (tau.max(axis=0) - tau.min(axis=0))
    noise = rng.normal(size=tau.shape) * sigma
    q_read = np.round(q / ENCODER_STEP) * ENCODER_STEP
    return dict(t=t, q=q, q_read=q_read, qd=qd, qdd=qdd, tau_rb=tau_rb, tau=tau, noise=noise, sigma=sigma,
                Fc=Fc, Fv=Fv)


def write_log(path, m, tau):
    n = m["q"].shape[1]
    header = ",".join(["t"] + [f"q{i + 1}" for i in range(n)] + [f"tau{i + 1}" for i in range(n)])
    np.savetxt(path, np.column_stack([m["t"], m["q_read"], tau]), delimiter=",", header=header, comments="",
               fmt="%.10g")


def generate(robots, out_dir, fs=250.0, seconds=30.0, seed=22, kappa=(3.0, 8.0)):
    """robots: list of (name, urdf path, trajectories, effects per trajectory). Writes the logs and
    cases.json into out_dir; returns the manifest."""
    os.makedirs(out_dir, exist_ok=True)
    master = np.random.default_rng(seed)
    manifest, kind_index = [], 0
    order = KINDS + ["coupling"]  # couplings twice as often: any ratio, any pair, either order
    for name, urdf, trajectories, per_trajectory in robots:
        arm = Arm(urdf)
        for k in range(trajectories):
            traj_seed = int(master.integers(1 << 31))
            rests = k % 2 == 1
            m = simulate(arm, traj_seed, rests, fs, seconds)
            clean = f"{name}_t{k + 1}_clean"
            write_log(os.path.join(out_dir, clean + ".csv"), m, m["tau"] + m["noise"])
            manifest.append(dict(name=clean, robot=name, log=clean + ".csv", clean_twin=clean, rests=rests, truth=None,
                                 sigma=m["sigma"].tolist()))
            cases = []
            for e in range(per_trajectory):
                kind = order[kind_index % len(order)]
                kind_index += 1
                cases.append((kind, np.random.default_rng(int(master.integers(1 << 31)))))
            for x, kind in enumerate(EXTRA_KINDS):
                cases.append((kind, np.random.default_rng([traj_seed, 1 + x])))
            for e, (kind, rng) in enumerate(cases):
                joints, shape = draw_effect(kind, arm, rng, m)
                col = effect_columns(kind, joints, shape, dict(m, rng=rng))
                size = rng.uniform(*kappa)
                # The effect's size in noise units: what the joints' own Coulomb and viscous columns
                # cannot take (unexplained). A coupled motor's friction is scaled to it from the
                # joint's own, which it replaces (that part is in the own columns' span: size 0).
                scale = size / unexplained(col, m["qd"], m["sigma"])
                tau = m["tau"] + m["noise"] + scale * col
                if kind == "coupled_motor":
                    j = joints[0] - 1
                    tau[:, j] -= m["Fc"][j] * _sgn(m["qd"][:, j]) + m["Fv"][j] * m["qd"][:, j]
                log = f"{name}_t{k + 1}_{e + 1}_{kind}_{'_'.join(str(j) for j in joints)}"
                write_log(os.path.join(out_dir, log + ".csv"), m, tau)
                manifest.append(dict(name=log, robot=name, log=log + ".csv", clean_twin=clean, rests=rests,
                                     truth=dict(kind=kind, joints=joints, shape=float(shape), coefficient=float(scale),
                                                kappa=float(size)),
                                     sigma=m["sigma"].tolist()))
    with open(os.path.join(out_dir, "cases.json"), "w") as f:
        json.dump(manifest, f, indent=1)
    return manifest


def default_robots(source_dir):
    u = lambda n: os.path.join(source_dir, "tests", "urdf", n + ".urdf")
    return [("arm3", u("arm3"), 3, 4), ("arm6", u("arm6"), 4, 5), ("cobot7", u("cobot7"), 3, 4)]


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--source-dir", default=os.path.join(os.path.dirname(__file__), "..", ".."))
    ap.add_argument("--out", required=True)
    ap.add_argument("--seed", type=int, default=22)
    ap.add_argument("--kappa", type=float, nargs=2, default=(3.0, 8.0), help="effect size range [noise std]")
    a = ap.parse_args()
    cases = generate(default_robots(a.source_dir), a.out, seed=a.seed, kappa=tuple(a.kappa))
    print(f"{len(cases)} logs in {a.out}")
