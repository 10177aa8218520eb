#!/usr/bin/env python3
"""Logs with effects outside diagnose's catalogue (issue 71): what a real arm produces that no
kind of the candidate table names. Same arms, trajectories, friction and noise as the hidden cases
(generate_logs.py: KDL's RNEA on the test URDFs, Eq. 7 friction, 20-bit encoders), one effect per
log, a clean twin per trajectory, two noise levels (the hidden cases' 0.5 % of each joint's torque
range, and three times that).

The kinds, each as a real arm makes it:
- torque_delay (measurement): joint j's torque channel lags the position channel by delta, 0.5 to 3
  samples (the current loop's filter, a bus that samples the drives one after another). The log's
  tau_j is the whole joint torque (rigid body and friction) at t - delta, computed exactly from the
  trajectory's clock, not interpolated.
- spring_balancer (transmission): a gas spring balancing joint j against gravity, anchored a and b
  from the axis: force k (L - L0) along L(q) = sqrt(a^2 + b^2 - 2 a b cos(q - q0)), torque
  k (L - L0) a b sin(q - q0) / L. Smooth in q, not one harmonic.
- thermal_coulomb (thermal): Coulomb friction rising as the gear warms, sgn(qd) (1 - exp(-t / T)),
  T of 5 to 15 s (the catalogue's drift is linear in t and multiplies qd).
- tight_spot (transmission wear): friction that rises over a stretch of travel, sgn(qd)
  exp(-((q - qc) / w)^2), w of 5 to 15 % of the joint's range in the log.
- sensor_saturation (sensor): a torque sensor or current channel whose gain falls with the load,
  -tau^3 / max|tau|^2 of joint j's own torque.
- cable_drag (transmission): a cable run through joint j pulled by the next joint's position,
  tanh((q_k - qc) / w) with k a neighbour of j.

A shape effect's size is set as the hidden cases' (generate_logs.unexplained): what the joint's own
Coulomb and viscous columns cannot take is kappa noise standard deviations, kappa uniform in [3, 8].
The manifest (outside_cases.json) gives each log's truth: kind, 1-based joints, delay [s] or shape
parameters, kappa, noise factor.
"""
import json
import os

import numpy as np

import generate_logs as g

KINDS = ["torque_delay", "spring_balancer", "thermal_coulomb", "tight_spot", "sensor_saturation", "cable_drag"]
NOISE_FACTORS = (1.0, 3.0)


def shifted_motion(arm, traj_seed, rests, fs, t, delay):
    """q, qd, qdd at t - delay of the trajectory generate_logs.simulate(arm, traj_seed, rests, ...)
    plays: the same Fourier series, the clock u evaluated at the shifted instants (on simulate's
    16x fine grid, linearly between its points; before the log's start u runs at speed 1)."""
    rng = np.random.default_rng(traj_seed)
    evaluate = g.fourier_excitation(arm, rng)
    ts = t - delay
    if not rests:
        u, w, wd = ts - t[0], np.ones_like(t), np.zeros_like(t)
    else:
        fine = np.linspace(t[0], t[-1], 16 * (len(t) - 1) + 1)
        uf, wf, wdf = g.motion_clock(fine + 0.5 / fs, True)  # u on the fine grid itself, u(t[0]) = 0
        u = np.where(ts < t[0], ts - t[0], np.interp(ts, fine, uf))
        w = np.interp(ts, fine, wf, left=1.0)
        wd = np.interp(ts, fine, wdf, left=0.0)
    q, qd_u, qdd_u = evaluate(u)
    qd = w[:, None] * qd_u
    qdd = (w ** 2)[:, None] * qdd_u + wd[:, None] * qd_u
    return q, qd, qdd


def shape_column(kind, j, rng, m, n):
    """Unit-size torque columns (S, n) of a shape effect on joint j (0-based); returns (columns,
    joints 1-based, shape parameters)."""
    S = m["q"].shape[0]
    out = np.zeros((S, n))
    q, qd = m["q"][:, j], m["qd"][:, j]
    lo, hi = q.min(), q.max()
    if kind == "spring_balancer":
        a, b = 1.0, rng.uniform(0.2, 0.5)
        q0 = rng.uniform(lo, hi)
        L = np.sqrt(a * a + b * b - 2 * a * b * np.cos(q - q0))
        L0 = rng.uniform(0.6, 0.9) * (a - b)
        out[:, j] = (L - L0) * a * b * np.sin(q - q0) / L
        return out, [j + 1], dict(b=b, q0=q0, L0=L0)
    if kind == "thermal_coulomb":
        T = rng.uniform(5.0, 15.0)
        out[:, j] = np.sign(qd) * (1 - np.exp(-(m["t"] - m["t"][0]) / T))
        return out, [j + 1], dict(T=T)
    if kind == "tight_spot":
        qc, w = rng.uniform(lo + 0.25 * (hi - lo), hi - 0.25 * (hi - lo)), rng.uniform(0.05, 0.15) * (hi - lo)
        out[:, j] = np.sign(qd) * np.exp(-((q - qc) / w) ** 2)
        return out, [j + 1], dict(qc=qc, w=w)
    if kind == "sensor_saturation":
        tau = m["tau"][:, j]
        out[:, j] = -tau ** 3 / np.abs(tau).max() ** 2
        return out, [j + 1], {}
    if kind == "cable_drag":
        k = j + 1 if j + 1 < n else j - 1
        qk = m["q"][:, k]
        lo_k, hi_k = qk.min(), qk.max()
        qc, w = rng.uniform(lo_k + 0.3 * (hi_k - lo_k), hi_k - 0.3 * (hi_k - lo_k)), rng.uniform(0.1, 0.25) * (hi_k - lo_k)
        out[:, j] = np.tanh((qk - qc) / w)
        return out, [j + 1], dict(neighbour=k + 1, qc=qc, w=w)
    raise ValueError(kind)


def delayed_torque(arm, traj_seed, rests, fs, m, j, delay):
    """Joint j's whole torque (rigid body and Eq. 7 friction) at t - delay."""
    q, qd, qdd = shifted_motion(arm, traj_seed, rests, fs, m["t"], delay)
    tau_rb = arm.torque(q, qd, qdd)
    return tau_rb[:, j] + m["Fc"][j] * np.sign(qd[:, j]) + m["Fv"][j] * qd[:, j]


def generate(robots, out_dir, fs=250.0, seconds=30.0, seed=71, kappa=(3.0, 8.0)):
    """robots: list of (name, urdf path). Per robot two trajectories (noise factors 1 and 3, the
    second with rests); the six kinds split between them, rotating with the robot. Writes the logs
    and outside_cases.json into out_dir; returns the manifest."""
    os.makedirs(out_dir, exist_ok=True)
    master = np.random.default_rng(seed)
    manifest = []
    for r, (name, urdf) in enumerate(robots):
        arm = g.Arm(urdf)
        for k, factor in enumerate(NOISE_FACTORS):
            traj_seed = int(master.integers(1 << 31))
            rests = k == 1
            m = g.simulate(arm, traj_seed, rests, fs, seconds)
            noise, sigma = factor * m["noise"], factor * m["sigma"]
            clean = f"{name}_n{factor:g}_clean"
            g.write_log(os.path.join(out_dir, clean + ".csv"), m, m["tau"] + noise)
            manifest.append(dict(name=clean, robot=name, log=clean + ".csv", clean_twin=clean, rests=rests,
                                 noise_factor=factor, truth=None))
            kinds = [KINDS[(i + r) % len(KINDS)] for i in range(k, len(KINDS), 2)]
            for kind in kinds:
                rng = np.random.default_rng(int(master.integers(1 << 31)))
                j = int(rng.integers(0, arm.n))
                tau = m["tau"] + noise
                truth = dict(kind=kind, joints=[j + 1])
                if kind == "torque_delay":
                    delay = rng.uniform(0.5, 3.0) / fs
                    tau[:, j] = delayed_torque(arm, traj_seed, rests, fs, m, j, delay) + noise[:, j]
                    truth.update(delay=delay, delay_samples=delay * fs)
                else:
                    col, joints, shape = shape_column(kind, j, rng, m, arm.n)
                    size = rng.uniform(*kappa)
                    scale = size / g.unexplained(col, m["qd"], sigma)
                    tau = tau + scale * col
                    truth.update(joints=joints, shape=shape, kappa=size, coefficient=float(scale))
                log = f"{name}_n{factor:g}_{kind}_{j + 1}"
                g.write_log(os.path.join(out_dir, log + ".csv"), m, tau)
                manifest.append(dict(name=log, robot=name, log=log + ".csv", clean_twin=clean, rests=rests,
                                     noise_factor=factor, truth=truth))
    with open(os.path.join(out_dir, "outside_cases.json"), "w") as f:
        json.dump(manifest, f, indent=1)
    return manifest


def default_robots(source_dir):
    u = lambda n: os.path.join(source_dir, "tests", "urdf", n + ".urdf")
    return [("arm3", u("arm3")), ("arm6", u("arm6")), ("cobot7", u("cobot7"))]
