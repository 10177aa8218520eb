#!/usr/bin/env python3
"""Progress on a terminal, none elsewhere (issue 72, host_sim/common/progress.hpp).

Runs dyncal diagnose (a hidden case of tests/hidden_cases/generate_logs.py on arm6, about 7 s) and
dyncal calibrate (the simulated er20 drive, lockstep) under script(1), which gives them a
pseudo-terminal: each output must hold the single updating progress line ("\\r", the task's name,
a bar). Not on a terminal (as in CI) there is none: tests/report_pages.py checks the diagnose and
calibrate runs it captures. The survey's progress on a terminal is checked by CTest
survey_quick_matches_committed.
Exit 0 when every check holds; otherwise each failed check on one line, exit 1.
"""
import argparse
import os
import shlex
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "support"))
import lockstep_drive  # noqa: E402

failures = []


def check(ok, message):
    if not ok:
        failures.append(message)


def on_terminal(cmd):
    """`cmd`'s output when its stdout and stderr are a pseudo-terminal (script -e: its exit code)."""
    p = subprocess.run(["script", "-qec", " ".join(shlex.quote(c) for c in cmd), "/dev/null"], capture_output=True)
    check(p.returncode == 0, f"{' '.join(cmd)} on a terminal: exit {p.returncode}")
    return p.stdout.decode("utf-8", "replace")  # bytes: text mode would turn the "\r" into newlines


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--dyncal", required=True)
    ap.add_argument("--source-dir", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    logs = os.path.join(a.out, "hidden")
    subprocess.run([sys.executable, os.path.join(a.source_dir, "tests", "hidden_cases", "generate_logs.py"),
                    "--source-dir", a.source_dir, "--out", logs], check=True, capture_output=True)
    diagnose = [a.dyncal, "diagnose", "--robots-dir", os.path.join(a.source_dir, "tests", "robots"), "--robot", "arm6",
                "--data", os.path.join(logs, "arm6_t2_4_stribeck_1.csv"), "--model", "eq7"]
    shown = on_terminal(diagnose)
    check("\rdiagnose: step 1, building candidates [" in shown, "diagnose on a terminal: no progress line")

    drive, uri = lockstep_drive.start(a.dyncal, a.out, "progress")
    try:
        shown = on_terminal([a.dyncal, "calibrate", "--drive", uri, "--no-flash"])
        check("\rexcitation run, streaming [" in shown, "calibrate on a terminal: no progress line")
    finally:
        lockstep_drive.stop(drive)
    for f in failures:
        print("FAILED: " + f)
    if not failures:
        print("progress lines on a terminal: diagnose, calibrate")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
