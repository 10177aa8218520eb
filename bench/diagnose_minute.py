#!/usr/bin/python3
"""Issue 68's diagnose benchmark (docs/performance.md, "A 7-joint minute at 1 kHz"): writes a cobot7
log of 60 s at 1 kHz with two undeclared effects of 6 noise units each (Stribeck on joint 6, load
friction on joint 1), and its clean twin, with the hidden cases' generator (tests/hidden_cases/
generate_logs.py: orocos-kdl's inverse dynamics of tests/urdf/cobot7.urdf).

Usage: bench/diagnose_minute.py OUT_DIR   (writes OUT_DIR/effects.csv and OUT_DIR/clean.csv), then
  /usr/bin/time -f "%e s" build/release/host_sim/dyncal_test_cli diagnose --robots-dir tests/robots \\
      --robot cobot7 --data OUT_DIR/effects.csv --model eq7
"""
import os
import sys

import numpy as np

SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, os.path.join(SOURCE, "tests", "hidden_cases"))
import generate_logs as g  # noqa: E402

KAPPA = 6.0  # each effect's unexplained part, in noise standard deviations


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    arm = g.Arm(os.path.join(SOURCE, "tests", "urdf", "cobot7.urdf"))
    m = g.simulate(arm, 5, False, 1000.0, 60.0)
    m["rng"] = np.random.default_rng(1)
    tau = m["tau"] + m["noise"]
    g.write_log(os.path.join(out, "clean.csv"), m, tau)
    extra = np.zeros_like(tau)
    for kind, joints, shape in (("stribeck", [6], 0.1 * np.abs(m["qd"][:, 5]).max()), ("load_friction", [1], 0.0)):
        col = g.effect_columns(kind, joints, shape, m)
        extra += col * KAPPA / g.unexplained(col, m["qd"], m["sigma"])
    g.write_log(os.path.join(out, "effects.csv"), m, tau + extra)
    return 0


if __name__ == "__main__":
    sys.exit(main())
