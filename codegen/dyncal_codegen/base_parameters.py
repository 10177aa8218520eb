"""Base parameters by numeric QR decomposition over random samples (Gautier 1990).

W stacks the standard regressor, plus one q_dd column per joint for rotor inertia when the robot
declares it, at random states. Columns are examined in a priority order (links 1..n; within a
link XX XY XZ YZ ZZ MX MY YY MZ M; rotor inertias last), so that the classical groupings come
out (XXR = XX - YY, ZZR = ZZ + YY, M and MZ of link j regrouped onto link j-1, Ia_1 into ZZR_1).
A column whose QR diagonal is below RANK_TOLERANCE * max|diag| depends on the preceding ones:
    W_dep = W_ind * Beta   =>   base parameters  phi_b = phi_ind + Beta * phi_dep .
"""
import math

import numpy as np

from .dynamics import PARAMS_PER_LINK

RANK_TOLERANCE = 1e-8
COEFFICIENT_CLEANUP = 1e-10
NUM_SAMPLES = 200
SEED = 20261121
WITHIN_LINK_ORDER = [0, 1, 2, 4, 5, 6, 7, 3, 8, 9]


def compile_program(defs, outputs, sym):
    """A Python function (q, qd, qdd) -> list of output values, from a traced program."""
    n = sym.n
    lines = ["def f(q, qd, qdd):"]
    for i in range(n):
        lines.append(f"    q{i + 1} = q[{i}]; c{i + 1} = math.cos(q[{i}]); s{i + 1} = math.sin(q[{i}])")
        lines.append(f"    qd{i + 1} = qd[{i}]; qdd{i + 1} = qdd[{i}]")
    for s, e in defs:
        lines.append(f"    {s} = {e}")
    lines.append("    return [" + ", ".join(str(o) for o in outputs) + "]")
    env = {"math": math}
    exec("\n".join(lines), env)
    return env["f"]


class BaseParameters:
    def __init__(self, independent, dependent, beta, rotor_independent, rotor_grouping, zero_columns):
        self.independent = independent  # standard indices kept, in base order
        self.dependent = dependent  # column indices (standard, or n_std + j for Ia_j)
        self.beta = beta  # (n_base x len(dependent))
        self.rotor_independent = rotor_independent  # joint -> bool
        self.rotor_grouping = rotor_grouping  # joint -> list of (base index, coefficient)
        self.zero_columns = zero_columns


def compute(Y_function, n, with_rotor_inertia, limits=None):
    rng = np.random.default_rng(SEED)
    n_std = PARAMS_PER_LINK * n
    n_cols = n_std + (n if with_rotor_inertia else 0)
    rows = []
    for _ in range(NUM_SAMPLES):
        q = rng.uniform(-math.pi, math.pi, n)
        qd = rng.uniform(-3, 3, n)
        qdd = rng.uniform(-10, 10, n)
        Y = np.array(Y_function(q, qd, qdd), dtype=float).reshape(n, n_std)
        if with_rotor_inertia:
            Y = np.hstack([Y, np.diag(qdd)])
        rows.append(Y)
    W = np.vstack(rows)
    order = [PARAMS_PER_LINK * k + c for k in range(n) for c in WITHIN_LINK_ORDER]
    order += list(range(n_std, n_cols))
    scale = np.linalg.norm(W, axis=0)
    zero = [c for c in range(n_cols) if scale[c] < RANK_TOLERANCE * scale.max()]
    order = [c for c in order if c not in zero]
    _, R = np.linalg.qr(W[:, order] / scale[order])
    diag = np.abs(np.diag(R))
    keep = diag > RANK_TOLERANCE * diag.max()
    independent = [c for c, k in zip(order, keep) if k]
    dependent = [c for c, k in zip(order, keep) if not k]
    Wi, Wd = W[:, independent], W[:, dependent]
    beta, *_ = np.linalg.lstsq(Wi, Wd, rcond=None)
    beta[np.abs(beta) < COEFFICIENT_CLEANUP] = 0.0
    # 12 significant digits: exact geometric products survive, floating-point noise does not, and
    # the generated text is stable across BLAS implementations.
    beta = np.vectorize(lambda x: float(f"{x:.12g}"))(beta)
    residual = np.linalg.norm(Wi @ beta - Wd) / max(np.linalg.norm(Wd), 1.0)
    if residual > 1e-8:
        raise RuntimeError(f"base-parameter reduction inexact (residual {residual:.2e})")
    # Standard columns kept in natural order for the generated code.
    std_ind = sorted(c for c in independent if c < n_std)
    perm = [independent.index(c) for c in std_ind]
    rotor_ind_cols = [c for c in independent if c >= n_std]
    beta_std = beta[perm, :]
    rotor_independent = [(n_std + j) in rotor_ind_cols for j in range(n)]
    rotor_grouping = {}
    for d_idx, c in enumerate(dependent):
        if c >= n_std:
            coeffs = [(b, beta_std[b, d_idx]) for b in range(len(std_ind)) if beta_std[b, d_idx] != 0.0]
            rotor_grouping[c - n_std] = coeffs
    std_dep = [(d_idx, c) for d_idx, c in enumerate(dependent) if c < n_std]
    beta_out = beta_std[:, [d for d, _ in std_dep]]
    return BaseParameters(std_ind, [c for _, c in std_dep], beta_out, rotor_independent, rotor_grouping, zero)
