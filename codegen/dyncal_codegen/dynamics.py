"""Rigid-body dynamics of a serial chain of revolute and prismatic joints, traced into straight-line
programs.

Conventions (Khalil-Kleinfinger, modified DH frames): link i's frame rotates with a revolute joint i
about its z axis, or slides with a prismatic one along it; standard parameters of link i, about the
frame origin and in link axes, are [XX XY XZ YY YZ ZZ MX MY MZ M] (Khalil & Kleinfinger 1986; Gautier & Khalil 1990).

Newton-Euler about the link origin makes the link wrench linear in the standard parameters:
    f = M a + w_dot x MS + w x (w x MS),   n = I w_dot + w x (I w) + MS x a,
with a the acceleration of the origin minus gravity. Joint i's torque (a force for a prismatic
joint) collects, for every link k >= i, the power of link k's wrench on joint i's unit screw
expressed in frame k (u, v); the screw starts as (z, 0) for a revolute joint, (0, z) for a prismatic:
    tau_i = sum_k  u_ik . n_k + v_ik . f_k .
A prismatic joint's offset p_i + q_i R_i z depends on q_i; its frame's origin acceleration gains the
relative terms 2 w x (qd z) + qdd z, its angular velocity none.
"""
import sympy as sp

from .description import PRISMATIC
from .tracer import Tracer

PARAMS_PER_LINK = 10


class Symbols:
    def __init__(self, n):
        self.n = n
        self.q = [sp.Symbol(f"q{i + 1}") for i in range(n)]
        self.c = [sp.Symbol(f"c{i + 1}") for i in range(n)]
        self.s = [sp.Symbol(f"s{i + 1}") for i in range(n)]
        self.qd = [sp.Symbol(f"qd{i + 1}") for i in range(n)]
        self.qdd = [sp.Symbol(f"qdd{i + 1}") for i in range(n)]
        self.phi = [sp.Symbol(f"phi{k}") for k in range(PARAMS_PER_LINK * n)]


def _rotations(tr, joints, sym):
    """R(i-1, i) = R_fixed * Rz(q_i) (revolute) or R_fixed (prismatic), entries traced; the origin
    p_i (+ q_i R_fixed z when prismatic) in the parent frame; and which joints are prismatic."""
    Rs, ps, prismatic = [], [], []
    for i, j in enumerate(joints):
        Rf = j.R
        p = [sp.nsimplify(x) if x == 0 else x for x in j.p]
        if j.kind == PRISMATIC:
            R = [[Rf[r, col] for col in range(3)] for r in range(3)]
            p = tr.vec([p[r] + sym.q[i] * Rf[r, 2] for r in range(3)])
        else:
            c, s = sym.c[i], sym.s[i]
            Rz = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
            R = [[tr.let(sum(Rf[r, k] * Rz[k][col] for k in range(3))) for col in range(3)] for r in range(3)]
        Rs.append(R)
        ps.append(p)
        prismatic.append(j.kind == PRISMATIC)
    return Rs, ps, prismatic


def _forward(tr, Rs, ps, prismatic, qd, qdd, gravity):
    """Angular velocity, angular acceleration and origin acceleration (minus gravity) per link."""
    n = len(Rs)
    w = [0, 0, 0]
    wd = [0, 0, 0]
    a = [-g for g in gravity]
    out = []
    for i in range(n):
        R, p = Rs[i], ps[i]
        acc_parent = tr.add(a, tr.add(tr.cross(wd, p), tr.cross(w, tr.cross(w, p))))
        a = tr.matTvec(R, acc_parent)
        w_in = tr.matTvec(R, w)
        wd_in = tr.matTvec(R, wd)
        z_qd = [0, 0, qd[i]]
        if prismatic[i]:
            w, wd = w_in, wd_in
            a = tr.add(a, tr.add(tr.cross([2 * x for x in w_in], z_qd), [0, 0, qdd[i]]))
        else:
            w = tr.add(w_in, z_qd)
            wd = tr.add(tr.add(wd_in, tr.cross(w_in, z_qd)), [0, 0, qdd[i]])
        out.append((w, wd, a))
    return out


def _inertia_columns(v):
    """L(v) with I v = L(v) [XX XY XZ YY YZ ZZ]: the six columns as 3-vectors."""
    return [[v[0], 0, 0], [v[1], v[0], 0], [v[2], 0, v[0]], [0, v[1], 0], [0, v[2], v[1]], [0, 0, v[2]]]


def link_wrench_columns(tr, w, wd, a):
    """The 10 columns (f, n) of the link wrench, linear in the standard parameters."""
    cols = []
    Lwd = _inertia_columns(wd)
    Lw = _inertia_columns(w)
    for c in range(6):
        n = tr.add(tr.vec(Lwd[c]), tr.cross(w, tr.vec(Lw[c])))
        cols.append(([0, 0, 0], n))
    for c in range(3):
        e = [0, 0, 0]
        e[c] = 1
        f = tr.add(tr.cross(wd, e), tr.cross(w, tr.cross(w, e)))
        n = tr.cross(e, a)
        cols.append((f, n))
    cols.append((list(a), [0, 0, 0]))
    return cols


def standard_regressor(joints, gravity):
    """Traced Y (n x 10n). Returns (tracer, Y as nested list of expressions, symbols)."""
    n = len(joints)
    sym = Symbols(n)
    tr = Tracer("x")
    Rs, ps, prismatic = _rotations(tr, joints, sym)
    kin = _forward(tr, Rs, ps, prismatic, sym.qd, sym.qdd, gravity)
    wrench_cols = [link_wrench_columns(tr, *kin[k]) for k in range(n)]
    Y = [[sp.Integer(0)] * (PARAMS_PER_LINK * n) for _ in range(n)]
    for i in range(n):
        u, v = ([0, 0, 0], [0, 0, 1]) if prismatic[i] else ([0, 0, 1], [0, 0, 0])
        for k in range(i, n):
            if k > i:
                v = tr.matTvec(Rs[k], tr.add(v, tr.cross(u, ps[k])))
                u = tr.matTvec(Rs[k], u)
            for c, (f, nn) in enumerate(wrench_cols[k]):
                Y[i][PARAMS_PER_LINK * k + c] = tr.let(tr.dot(u, nn) + tr.dot(v, f))
    return tr, Y, sym


def _link_wrench(tr, kin_k, phi_k):
    cols = link_wrench_columns(tr, *kin_k)
    f = tr.vec([sum(col[0][r] * phi_k[c] for c, col in enumerate(cols)) for r in range(3)])
    nn = tr.vec([sum(col[1][r] * phi_k[c] for c, col in enumerate(cols)) for r in range(3)])
    return f, nn


def _backward(tr, Rs, ps, prismatic, wrenches):
    """Recursive Newton-Euler backward pass: joint torques (forces for prismatic joints) from link
    wrenches."""
    n = len(Rs)
    tau = [None] * n
    F, N = [0, 0, 0], [0, 0, 0]
    for k in reversed(range(n)):
        f, nn = wrenches[k]
        if k + 1 < n:
            RF = tr.matvec(Rs[k + 1], F)
            N = tr.add(nn, tr.add(tr.matvec(Rs[k + 1], N), tr.cross(ps[k + 1], RF)))
            F = tr.add(f, RF)
        else:
            F, N = f, nn
        tau[k] = F[2] if prismatic[k] else N[2]
    return tau


def inverse_dynamics(joints, gravity):
    """Traced tau(q, qd, qdd, phi) by recursive Newton-Euler. Returns (tracer, tau list, symbols)."""
    n = len(joints)
    sym = Symbols(n)
    tr = Tracer("x")
    Rs, ps, prismatic = _rotations(tr, joints, sym)
    kin = _forward(tr, Rs, ps, prismatic, sym.qd, sym.qdd, gravity)
    wrenches = [_link_wrench(tr, kin[k], sym.phi[PARAMS_PER_LINK * k:PARAMS_PER_LINK * (k + 1)]) for k in range(n)]
    return tr, _backward(tr, Rs, ps, prismatic, wrenches), sym


def mass_matrix(joints):
    """Traced lower triangle of M(q, phi): column j is the torque for qdd = e_j, qd = 0, no gravity."""
    n = len(joints)
    sym = Symbols(n)
    tr = Tracer("x")
    Rs, ps, prismatic = _rotations(tr, joints, sym)
    M = {}
    zeros = [0] * n
    for j in range(n):
        unit = [1 if i == j else 0 for i in range(n)]
        kin = _forward(tr, Rs, ps, prismatic, zeros, unit, [0, 0, 0])
        wrenches = [_link_wrench(tr, kin[k], sym.phi[PARAMS_PER_LINK * k:PARAMS_PER_LINK * (k + 1)]) for k in range(n)]
        tau = _backward(tr, Rs, ps, prismatic, wrenches)
        for i in range(j, n):
            M[(i, j)] = tau[i]
    return tr, M, sym
