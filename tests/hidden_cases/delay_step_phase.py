#!/usr/bin/env python3
"""A torque delay on a log with rests, the rests' acceleration steps at four sub-sample phases
(docs/diagnose.md "A delay read from sampled steps").

arm6 with rests (generate_logs.simulate's motion clock, shifted by 0, 1/4, 1/2 and 3/4 of a sample),
joint 1's torque channel 2.8 samples late (outside_effects.delayed_torque), diagnosed with
`--model eq7`. The reading follows the steps' phase over about a sample (each sampled step is placed
only to within a sample, all at one phase); its 95 % interval must hold the truth at every phase.
Prints each log's delay and interval against the truth; exit 1 when a delay is not found or its
interval misses the truth.
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

FS, SECONDS, TRAJECTORY, DELAY_SAMPLES = 250.0, 30.0, 12, 2.8


def main():
    a = runner_arguments(__doc__.split("\n")[0], 12).parse_args()
    os.makedirs(a.out, exist_ok=True)
    arm = g.Arm(dict(o.default_robots(a.source_dir))["arm6"])
    clock = g.motion_clock
    delay = DELAY_SAMPLES / FS
    failed = False
    for quarter in range(4):
        shift = quarter / 4 / FS
        g.motion_clock = lambda t, rests, s=shift, **kw: clock(t + s, rests, **kw)
        m = g.simulate(arm, a.seed, True, FS, SECONDS)
        tau = m["tau"] + m["noise"]
        tau[:, 0] = o.delayed_torque(arm, a.seed, True, FS, m, 0, delay) + m["noise"][:, 0]
        log = os.path.join(a.out, f"phase_{quarter}.csv")
        g.write_log(log, m, tau)
        report = log.replace(".csv", ".json")
        subprocess.run([a.dyncal, "diagnose", "--robots-dir", os.path.join(a.source_dir, "tests", "robots"),
                        "--robot", "arm6", "--data", log, "--model", "eq7", "--report", report],
                       check=True, capture_output=True)
        with open(report) as f:
            found = [e for e in json.load(f)["effects"] if e["kind"] == "torque_delay" and e["joints"] == [1]]
        reading = (f"{found[0]['shape'] * 1e3:.2f} ms (95 % {found[0]['shape_interval'][0] * 1e3:.2f}.."
                   f"{found[0]['shape_interval'][1] * 1e3:.2f})" if found else "no delay found")
        print(f"steps shifted by {quarter}/4 sample: joint 1 delay {reading}, truth {delay * 1e3:.2f} ms")
        held = found and found[0]["shape_interval"][0] <= delay <= found[0]["shape_interval"][1]
        failed = failed or not held
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
