#!/usr/bin/env python3
"""A torque delay on a log with rests, the rests' acceleration steps at four sub-sample phases
(docs/diagnose.md "A delay read from sampled steps").

arm6 with rests (generate_logs.simulate's motion clock, shifted by 0, 1/4, 1/2 and 3/4 of a sample),
joint 1's torque channel 2.8 samples late (outside_effects.delayed_torque), diagnosed with
`--model eq7`. The reading follows the steps' phase over about a sample (each sampled step is placed
only to within a sample, all at one phase); its 95 % interval must hold the truth at every phase.
Then half a sample on joint 3 at the first phase: with its steps' share of half a sample added, the
interval would hold 0, so the delay must be read away from the steps (the report's note says so).
Prints each log's delay and interval against the truth; exit 1 when a delay is not found, its
interval misses the truth, or the half-sample one is not read away from the steps.
"""
import json
import os
import subprocess
import sys

sys.dont_write_bytecode = True  # nothing written into the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import generate_logs as g  # noqa: E402
import outside_effects as o  # noqa: E402
from run_cases import runner_arguments  # noqa: E402

FS, SECONDS, TRAJECTORY, DELAY_SAMPLES, HALF_SAMPLE_JOINT = 250.0, 30.0, 12, 2.8, 3


def diagnose(a, arm, name, joint, delay):
    """Diagnoses a log with joint `joint`'s (1-based) torque `delay` [s] late: (delay found or None,
    the report's notes)."""
    m = g.simulate(arm, a.seed, True, FS, SECONDS)
    tau = m["tau"] + m["noise"]
    tau[:, joint - 1] = o.delayed_torque(arm, a.seed, True, FS, m, joint - 1, delay) + m["noise"][:, joint - 1]
    log = os.path.join(a.out, f"{name}.csv")
    g.write_log(log, m, tau)
    report = log.replace(".csv", ".json")
    subprocess.run([a.dyncal, "diagnose", "--robots-dir", os.path.join(a.source_dir, "tests", "robots"),
                    "--robot", "arm6", "--data", log, "--model", "eq7", "--report", report],
                   check=True, capture_output=True)
    with open(report) as f:
        r = json.load(f)
    found = [e for e in r["effects"] if e["kind"] == "torque_delay" and e["joints"] == [joint]]
    return (found[0] if found else None), r["notes"]


def held(name, joint, delay, found):
    """Prints the reading; whether the delay was found with the truth inside its interval."""
    reading = (f"{found['shape'] * 1e3:.2f} ms (95 % {found['shape_interval'][0] * 1e3:.2f}.."
               f"{found['shape_interval'][1] * 1e3:.2f})" if found else "no delay found")
    print(f"{name}: joint {joint} delay {reading}, truth {delay * 1e3:.2f} ms")
    return bool(found) and found["shape_interval"][0] <= delay <= found["shape_interval"][1]


def main():
    a = runner_arguments(__doc__.split("\n")[0], TRAJECTORY).parse_args()
    os.makedirs(a.out, exist_ok=True)
    arm = g.Arm(dict(o.default_robots(a.source_dir))["arm6"])
    clock = g.motion_clock
    failed = False
    for quarter in range(4):
        shift = quarter / 4 / FS
        g.motion_clock = lambda t, rests, s=shift, **kw: clock(t + s, rests, **kw)
        found, _ = diagnose(a, arm, f"phase_{quarter}", 1, DELAY_SAMPLES / FS)
        failed = not held(f"steps shifted by {quarter}/4 sample", 1, DELAY_SAMPLES / FS, found) or failed
    g.motion_clock = clock
    found, notes = diagnose(a, arm, "half_sample", HALF_SAMPLE_JOINT, 0.5 / FS)
    failed = not held("half a sample", HALF_SAMPLE_JOINT, 0.5 / FS, found) or failed
    away = [n for n in notes if n.startswith(f"joint {HALF_SAMPLE_JOINT}'s delay") and "read away from them" in n]
    print(f"half a sample: {away[0] if away else 'not read away from the steps'}")
    return 1 if failed or not away else 0


if __name__ == "__main__":
    sys.exit(main())
