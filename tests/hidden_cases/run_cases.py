#!/usr/bin/env python3
"""Hidden-case self test of `dyncal diagnose` (issue 22, docs/diagnose.md "Hidden cases").

Generates the logs (generate_logs.py: KDL's RNEA on the test URDFs, one undeclared effect per log,
clean twins), diagnoses every log with the declared model of the generator (`--model eq7`), and
scores each report against the truth:
- right: the first effect is the true kind on the true joints (a coupling's pair in either order,
  as a motor on q_i + r q_j is one on q_j + q_i / r), or the report names the true kind as
  indistinguishable from the one it chose (`indistinguishable_from`: the data cannot tell them
  apart, e.g. an offset and asymmetric Coulomb friction on a joint that never rests);
- excess cut: on the affected joints, the validation RMS in excess of the clean twin's, summed
  relative to the twin's, falls by at least half;
- harm: no other joint's validation RMS ends more than 10 % above its declared model's;
- clean logs: nothing added.
Targets: right on >= 90 % of the cases, excess cut on >= 90 %, no harm on any, nothing added on every
clean log. Exit 1 when a target is missed; the table goes to stdout and SUMMARY.md in the output folder.
"""
import argparse
import concurrent.futures
import json
import os
import subprocess
import sys
import time

sys.dont_write_bytecode = True  # nothing written into the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import generate_logs  # noqa: E402

RIGHT_TARGET, CUT_TARGET = 0.9, 0.9


def diagnose(dyncal, robots_dir, out, case):
    report = os.path.join(out, case["name"] + ".report.json")
    cmd = [dyncal, "diagnose", "--robots-dir", robots_dir, "--robot", case["robot"], "--data",
           os.path.join(out, case["log"]), "--model", "eq7", "--report", report]
    start = time.monotonic()
    p = subprocess.run(cmd, capture_output=True, text=True)
    seconds = time.monotonic() - start
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr}")
    with open(report) as f:
        return json.load(f), seconds


def same_effect(effect, truth):
    if truth["kind"] == "coupled_motor":  # the motor's own joint first
        return effect["kind"] == "coupled_motor" and effect["joints"] == truth["joints"]
    if truth["kind"] == "coupling":
        return effect["kind"] == "coupling" and sorted(effect["joints"]) == sorted(truth["joints"])
    return effect["kind"] == truth["kind"] and effect["joints"] == truth["joints"]


def found(report, truth):
    """'right', 'ambiguous' (the truth named as indistinguishable from the first effect) or 'wrong'."""
    if not report["effects"]:
        return "wrong"
    first = report["effects"][0]
    if same_effect(first, truth):
        return "right"
    joints_match = sorted(first["joints"]) == sorted(truth["joints"])
    if joints_match and truth["kind"] in first.get("indistinguishable_from", []):
        return "ambiguous"
    return "wrong"


def rms(report, key):
    return {j["joint"]: j[key] for j in report["joints"]}


def describe(effect):
    s = f"{effect['kind']} {'+'.join(str(j) for j in effect['joints'])}"
    if effect["kind"] in ("coupling", "coupled_motor"):
        s += f" r={effect['sign'] * effect['shape']:.3g}"
    elif effect["kind"] in ("stribeck", "position_periodic"):
        s += f" {effect['shape']:.3g}"
    return s


def score(manifest, reports):
    rows, clean_rows = [], []
    by_name = {c["name"]: c for c in manifest}
    for case in manifest:
        rep, seconds = reports[case["name"]]
        before, after = rms(rep, "rms_validation_before"), rms(rep, "rms_validation_after")
        if case["truth"] is None:
            clean_rows.append(dict(name=case["name"], added=[describe(e) for e in rep["effects"]], seconds=seconds))
            continue
        truth = case["truth"]
        twin = rms(reports[by_name[case["clean_twin"]]["name"]][0], "rms_validation_after")
        affected = truth["joints"]
        excess_before = sum(max(before[j] - twin[j], 0) / twin[j] for j in affected)
        excess_after = sum(max(after[j] - twin[j], 0) / twin[j] for j in affected)
        cut = 1 - excess_after / excess_before if excess_before > 0 else 0.0
        harm = max([after[j] / before[j] - 1 for j in before if j not in affected] or [0.0])
        shape = truth["shape"]
        rows.append(dict(name=case["name"], truth=f"{truth['kind']} {'+'.join(str(j) for j in affected)}"
                         + (f" r={shape:.3g}" if truth["kind"] in ("coupling", "coupled_motor") else
                            f" {shape:.3g}" if truth["kind"] in ("stribeck", "position_periodic") else ""),
                         kappa=truth["kappa"], verdict=found(rep, truth),
                         first=describe(rep["effects"][0]) if rep["effects"] else "-",
                         more=len(rep["effects"]) - 1 if rep["effects"] else 0,
                         excess_before=excess_before, cut=cut, harm=harm, seconds=seconds))
    return rows, clean_rows


def summary(rows, clean_rows):
    n = len(rows)
    right = sum(r["verdict"] != "wrong" for r in rows)
    cut = sum(r["cut"] >= 0.5 for r in rows)
    harmed = [r for r in rows if r["harm"] > 0.10]
    clean_added = [r for r in clean_rows if r["added"]]
    lines = ["| log | truth (κ) | first effect found (more) | verdict | excess before | excess cut | worst other joint |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['name']} | {r['truth']} ({r['kappa']:.1f}) | {r['first']} ({r['more']}) | {r['verdict']} | "
                     f"{100 * r['excess_before']:.0f} % | {100 * r['cut']:.0f} % | {100 * r['harm']:+.1f} % |")
    lines += ["", "| clean log | effects added |", "|---|---|"]
    lines += [f"| {r['name']} | {', '.join(r['added']) or 'none'} |" for r in clean_rows]
    seconds = [r["seconds"] for r in rows + clean_rows]
    lines += ["", f"Right effect on the right joints: {right} of {n} ({100 * right / n:.0f} %; "
              f"{sum(r['verdict'] == 'ambiguous' for r in rows)} named as indistinguishable); target >= 90 %.",
              f"Excess validation RMS cut by >= 50 %: {cut} of {n} ({100 * cut / n:.0f} %); target >= 90 %.",
              f"Another joint more than 10 % worse: {len(harmed)} of {n}; target 0.",
              f"Clean logs with an effect added: {len(clean_added)} of {len(clean_rows)}; target 0.",
              f"diagnose per log: median {sorted(seconds)[len(seconds) // 2]:.1f} s, max {max(seconds):.1f} s."]
    ok = right >= RIGHT_TARGET * n and cut >= CUT_TARGET * n and not harmed and not clean_added
    return "\n".join(lines), ok


def runner_arguments(description, seed):
    """The options every runner of generated cases takes: --dyncal, --source-dir, --out, --jobs, --seed."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--dyncal", required=True)
    ap.add_argument("--source-dir", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--seed", type=int, default=seed)
    return ap


def diagnose_all(dyncal, robots_dir, out, manifest, jobs):
    """Every case's (report, seconds) by name, `jobs` diagnoses at a time."""
    with concurrent.futures.ThreadPoolExecutor(jobs) as pool:
        futures = {c["name"]: pool.submit(diagnose, dyncal, robots_dir, out, c) for c in manifest}
        return {name: f.result() for name, f in futures.items()}


def main():
    ap = runner_arguments(__doc__.split("\n")[0], 22)
    ap.add_argument("--kappa", type=float, nargs=2, default=(3.0, 8.0),
                    help="range of the effects' unexplained RMS [noise standard deviations]")
    a = ap.parse_args()
    manifest = generate_logs.generate(generate_logs.default_robots(a.source_dir), a.out, seed=a.seed,
                                      kappa=tuple(a.kappa))
    reports = diagnose_all(a.dyncal, os.path.join(a.source_dir, "tests", "robots"), a.out, manifest, a.jobs)
    text, ok = summary(*score(manifest, reports))
    with open(os.path.join(a.out, "SUMMARY.md"), "w") as f:
        f.write(text + "\n")
    print(text)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
