#!/usr/bin/env python3
"""Outside-the-catalogue self test of `dyncal diagnose` (issue 71, docs/diagnose.md "Effects outside
the catalogue").

Generates the logs (outside_effects.py: one effect no candidate kind names per log, clean twins, two
noise levels), diagnoses each with the generator's declared model (`--model eq7`) and scores each
report against the truth:
- excess cut: on the affected joint, the validation RMS in excess of the clean twin's, relative to
  the twin's, falls by at least half (what the clean twin's fit has left is the best the log allows);
- harm: no other joint's validation RMS ends more than 10 % above its declared model's;
- through the model: `identify --effects report.json` (a shape fitted as a model term, a delay undone
  on the log) cuts the joint's excess validation RMS over the clean twin's identify by at least half;
  and `predict` with those parameters cuts the excess RMS on the log over the clean twin's by at least
  half (where predict applies what was found: not a delay, not a shape of time);
- delay: a torque_delay case's joint carries a torque_delay effect whose 95 % interval holds the true
  delay, and identify --effects cuts its excess by at least half;
- clean logs: nothing added.
Targets: excess cut with no harm, through identify and through predict, each on >= 80 % of the cases;
every delay found with its interval holding the truth and undone by identify; nothing added on every
clean log. Exit 1 when a target is missed; the table goes to stdout
and OUTSIDE.md in the output folder.
"""
import concurrent.futures
import json
import os
import subprocess
import sys

sys.dont_write_bytecode = True  # nothing written into the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import outside_effects  # noqa: E402
from run_cases import diagnose_all, rms, runner_arguments  # noqa: E402

CUT_TARGET = 0.8


def describe(effect):
    s = f"{effect['kind']} {'+'.join(str(j) for j in effect['joints'])}"
    if effect["kind"] == "torque_delay":
        lo, hi = effect["shape_interval"]
        s += f" {1e3 * effect['shape']:.2f} ms ({1e3 * lo:.2f}..{1e3 * hi:.2f})"
    elif effect["kind"] == "shape":
        s += f" of {effect['variable']}"
    return s


def delay_found(report, truth):
    """Whether a torque_delay effect on the true joint has a 95 % interval holding the true delay."""
    for e in report["effects"]:
        if e["kind"] == "torque_delay" and e["joints"] == truth["joints"]:
            lo, hi = e["shape_interval"]
            return lo <= truth["delay"] <= hi
    return False


def identify_rms(dyncal, robots_dir, out, case, tag, effects=None):
    """identify --model eq7 on a case's log (with a diagnosis report's effects): validation RMS per
    joint; its report is out/<tag>.identify.json, its parameters out/<tag>.params.json."""
    report = os.path.join(out, tag + ".identify.json")
    cmd = [dyncal, "identify", "--robots-dir", robots_dir, "--robot", case["robot"], "--data",
           os.path.join(out, case["log"]), "--model", "eq7", "--report", report,
           "--params", os.path.join(out, tag + ".params.json")]
    if effects:
        cmd += ["--effects", effects]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr}")
    with open(report) as f:
        return {j["joint"]: j["rms_validation"] for j in json.load(f)["joints"]}


def predict_rms(dyncal, robots_dir, out, case, tag):
    """predict with out/<tag>.params.json on a case's log: RMS per joint."""
    report = os.path.join(out, tag + ".predict.json")
    cmd = [dyncal, "predict", "--robots-dir", robots_dir, "--data", os.path.join(out, case["log"]),
           "--params", os.path.join(out, tag + ".params.json"), "--report", report]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr}")
    with open(report) as f:
        return {j["joint"]: j["rms_validation"] for j in json.load(f)["joints"]}


def share_cut(clean, before, after):
    excess = max(before - clean, 0)
    return 1 - max(after - clean, 0) / excess if excess > 0 else 0.0


def through_the_model(dyncal, robots_dir, out, case, twin, report):
    """The loop closed through the model: the share of the affected joint's excess RMS (over the clean
    twin's) that (1) identify --effects report.json removes from the validation RMS and (2) predict
    with those parameters removes on the log (None where predict cannot apply what was found: a delay
    is undone on the log, a shape of time is not applied to a log; model_effects.hpp)."""
    j = case["truth"]["joints"][0]
    name = case["name"]
    identify = [identify_rms(dyncal, robots_dir, out, c, tag, effects)[j] for c, tag, effects in
                ((twin, name + ".twin", None), (case, name, None),
                 (case, name + ".effects", os.path.join(out, name + ".report.json")))]
    applies = not any(e["kind"] == "torque_delay" or (e["kind"] == "shape" and e["variable"].endswith("t"))
                      for e in report["effects"])
    if not applies:
        return share_cut(*identify), None
    predict = [predict_rms(dyncal, robots_dir, out, c, tag)[j] for c, tag in
               ((twin, name + ".twin"), (case, name), (case, name + ".effects"))]
    return share_cut(*identify), share_cut(*predict)


def score(manifest, reports, loop):
    rows, clean_rows = [], []
    by_name = {c["name"]: c for c in manifest}
    for case in manifest:
        rep, seconds = reports[case["name"]]
        effects = [describe(e) for e in rep["effects"]]
        if case["truth"] is None:
            clean_rows.append(dict(name=case["name"], added=effects, seconds=seconds))
            continue
        truth = case["truth"]
        before, after = rms(rep, "rms_validation_before"), rms(rep, "rms_validation_after")
        twin = rms(reports[by_name[case["clean_twin"]]["name"]][0], "rms_validation_after")
        affected = truth["joints"]
        excess_before = sum(max(before[j] - twin[j], 0) / twin[j] for j in affected)
        excess_after = sum(max(after[j] - twin[j], 0) / twin[j] for j in affected)
        cut = 1 - excess_after / excess_before if excess_before > 0 else 0.0
        harm = max([after[j] / before[j] - 1 for j in before if j not in affected] or [0.0])
        size = (f"{truth['delay_samples']:.2f} samples" if truth["kind"] == "torque_delay"
                else f"κ {truth['kappa']:.1f}")
        is_delay = truth["kind"] == "torque_delay"
        rows.append(dict(name=case["name"], truth=f"{truth['kind']} {truth['joints'][0]} ({size})",
                         found=", ".join(effects) or "-", excess_before=excess_before, cut=cut, harm=harm,
                         delay_ok=delay_found(rep, truth) and loop[case["name"]][0] >= 0.5 if is_delay else None,
                         identify=loop[case["name"]][0], predict=loop[case["name"]][1], seconds=seconds))
    return rows, clean_rows


def summary(rows, clean_rows):
    n = len(rows)
    good = [r for r in rows if r["cut"] >= 0.5 and r["harm"] <= 0.10]
    identified = [r for r in rows if r["identify"] >= 0.5]
    predicted = [r for r in rows if r["predict"] is not None]
    predicted_ok = [r for r in predicted if r["predict"] >= 0.5]
    delays = [r for r in rows if r["delay_ok"] is not None]
    delays_ok = [r for r in delays if r["delay_ok"]]
    clean_added = [r for r in clean_rows if r["added"]]
    lines = ["| log | truth | effects found | excess before | excess cut | worst other joint | identify --effects | "
             "predict |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        predict = f"{100 * r['predict']:.0f} %" if r["predict"] is not None else "-"
        lines.append(f"| {r['name']} | {r['truth']} | {r['found']} | {100 * r['excess_before']:.0f} % | "
                     f"{100 * r['cut']:.0f} % | {100 * r['harm']:+.1f} % | {100 * r['identify']:.0f} % | {predict} |")
    lines += ["", "| clean log | effects added |", "|---|---|"]
    lines += [f"| {r['name']} | {', '.join(r['added']) or 'none'} |" for r in clean_rows]
    seconds = [r["seconds"] for r in rows + clean_rows]
    lines += ["", f"Excess validation RMS cut by >= 50 % with no other joint > 10 % worse: {len(good)} of {n} "
              f"({100 * len(good) / n:.0f} %); target >= {100 * CUT_TARGET:.0f} %.",
              f"Through identify --effects (its validation RMS, excess over the clean twin's identify cut by >= 50 %): "
              f"{len(identified)} of {n}; target >= {100 * CUT_TARGET:.0f} %.",
              f"Through predict with those parameters (where it applies them: no delay, no shape of time; excess "
              f"over the clean twin's cut by >= 50 %): {len(predicted_ok)} of {len(predicted)}; target >= "
              f"{100 * CUT_TARGET:.0f} %.",
              f"Delays found with the truth inside the 95 % interval and undone by identify --effects (>= 50 % of "
              f"the excess): {len(delays_ok)} of {len(delays)}; target all.",
              f"Clean logs with an effect added: {len(clean_added)} of {len(clean_rows)}; target 0.",
              f"diagnose per log: median {sorted(seconds)[len(seconds) // 2]:.1f} s, max {max(seconds):.1f} s."]
    ok = (len(good) >= CUT_TARGET * n and len(identified) >= CUT_TARGET * n and
          len(predicted_ok) >= CUT_TARGET * len(predicted) and len(delays_ok) == len(delays) and not clean_added)
    return "\n".join(lines), ok


def main():
    a = runner_arguments(__doc__.split("\n")[0], 71).parse_args()
    manifest = outside_effects.generate(outside_effects.default_robots(a.source_dir), a.out, seed=a.seed)
    robots_dir = os.path.join(a.source_dir, "tests", "robots")
    reports = diagnose_all(a.dyncal, robots_dir, a.out, manifest, a.jobs)
    by_name = {c["name"]: c for c in manifest}
    affected = [c for c in manifest if c["truth"]]
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        futures = {c["name"]: pool.submit(through_the_model, a.dyncal, robots_dir, a.out, c, by_name[c["clean_twin"]],
                                          reports[c["name"]][0]) for c in affected}
        loop = {name: f.result() for name, f in futures.items()}
    text, ok = summary(*score(manifest, reports, loop))
    with open(os.path.join(a.out, "OUTSIDE.md"), "w") as f:
        f.write(text + "\n")
    print(text)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
