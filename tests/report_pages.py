#!/usr/bin/env python3
"""The HTML pages and gates in a real browser (issue 72, docs/report.md, docs/gates.md).

Runs dyncal identify (the TX40 example), predict, monitor, diagnose (a hidden case of
tests/hidden_cases/generate_logs.py), calibrate (the simulated er20 drive, lockstep) and payload (a
2 kg load on a second simulated drive's arm, from its log) with --report, --html and gates, then
loads each page in headless Chromium (Debian's chromium) and checks:
- the DOM Chromium built has the expected plots (img.plot, data-plot names), each an embedded SVG
  (data:image/svg+xml) that decodes to an <svg>; no <script>, no http(s) address anywhere;
- no request: Chromium's net log holds no URL but its own background services', and its console
  (where a Content-Security-Policy refusal or a failed load is reported) holds no message;
- every number on the page (data-path: its JSON pointer) is the JSON report's number, as printed
  (%.6g, integers in full);
- a screenshot of the page's top is kept in --out as the test's artefact;
- no command prints a progress line, its output not being a terminal;
- the gates: the TX40 station gate file passes (exit 0), the strict one fails (exit 1) with the
  failed items named on stdout and in the report's "gate"; a payload gate around the true mass
  passes, one that excludes it fails.
Exit 0 when every check holds; otherwise each failed check on one line, exit 1.
"""
import argparse
import base64
import html.parser
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "support"))
import lockstep_drive  # noqa: E402

# Hosts Chromium itself contacts in the background (updates, time, accounts, dictionaries): not
# the page's requests.
BROWSER_HOSTS = re.compile(r"https?://([a-z0-9.-]+\.)?(google\.com|googleapis\.com|gvt1\.com|gstatic\.com)[/:]")
CHROMIUM_FLAGS = ["--headless=new", "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--enable-logging=stderr",
                  "--v=0", "--disable-background-networking", "--disable-component-update", "--disable-sync",
                  "--no-first-run", "--disable-default-apps", "--disable-extensions"]

failures = []


def check(ok, message):
    if not ok:
        failures.append(message)
    return ok


def run(cmd, expect):
    """Runs `cmd` with its output captured (not a terminal): it must exit `expect` and print no
    progress line (host_sim/common/progress.hpp draws one on a terminal only)."""
    p = subprocess.run(cmd, capture_output=True)
    out, err = (x.decode("utf-8", "replace") for x in (p.stdout, p.stderr))  # bytes: a "\r" stays one
    check(p.returncode == expect, f"{' '.join(cmd)}: exit {p.returncode}, expected {expect}\n{err.strip()}")
    check("\r" not in out + err, f"{' '.join(cmd[:2])}: a progress line although its output is not a terminal")
    return subprocess.CompletedProcess(cmd, p.returncode, out, err)


class Dom(html.parser.HTMLParser):
    """The elements the checks read: img.plot, scripts, every attribute, data-path texts."""

    def __init__(self):
        super().__init__()
        self.plots, self.scripts, self.urls, self.numbers = [], 0, [], []
        self._path = None
        self._text = ""

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "script":
            self.scripts += 1
        if tag == "img" and "plot" in (a.get("class") or "").split():
            self.plots.append((a.get("data-plot"), a.get("src") or ""))
        for k, v in attrs:
            if v and re.search(r"\bhttps?://", v) and not (v.startswith("data:")):
                self.urls.append(f"{tag} {k}={v[:80]}")
        if "data-path" in a:
            self._path, self._text = a["data-path"], ""

    def handle_data(self, data):
        if self._path is not None:
            self._text += data

    def handle_endtag(self, tag):
        if self._path is not None and tag == "span":
            self.numbers.append((self._path, self._text.strip()))
            self._path = None


def pointer(doc, path):
    for part in path.split("/")[1:]:
        part = part.replace("~1", "/").replace("~0", "~")
        doc = doc[int(part)] if isinstance(doc, list) else doc[part]
    return doc


def printed(v):
    if float(v).is_integer() and abs(v) < 1e15:
        return "%.0f" % v
    return "%.6g" % v


def chromium(page, out_dir, name):
    """Loads `page` twice (the DOM, then a screenshot). Returns (dom text, net-log URLs, console lines)."""
    profile = tempfile.mkdtemp(prefix="dyncal-chromium-")
    netlog = os.path.join(out_dir, name + ".netlog.json")
    try:
        p = subprocess.run(["chromium", *CHROMIUM_FLAGS, f"--user-data-dir={profile}", f"--log-net-log={netlog}",
                            "--dump-dom", "file://" + os.path.abspath(page)],
                           capture_output=True, text=True, timeout=120)
        check(p.returncode == 0, f"{name}: chromium --dump-dom exit {p.returncode}")
        shot = os.path.join(out_dir, name + ".png")
        s = subprocess.run(["chromium", *CHROMIUM_FLAGS, f"--user-data-dir={profile}", "--window-size=1000,1400",
                            f"--screenshot={shot}", "file://" + os.path.abspath(page)],
                           capture_output=True, text=True, timeout=120)
        check(s.returncode == 0 and os.path.exists(shot) and os.path.getsize(shot) > 10000,
              f"{name}: no screenshot ({shot})")
    finally:
        shutil.rmtree(profile, ignore_errors=True)
    urls = []
    if os.path.exists(netlog):
        with open(netlog, encoding="utf-8", errors="replace") as f:
            urls = sorted(set(re.findall(r'"url":"([^"]*)"', f.read())))
    console = [line for line in (p.stderr + s.stderr).splitlines() if ":CONSOLE" in line]
    return p.stdout, urls, console


def check_page(name, page, report_path, expected_plots, out_dir):
    with open(report_path) as f:
        report = json.load(f)
    dom_text, urls, console = chromium(page, out_dir, name)
    dom = Dom()
    dom.feed(dom_text)
    names = [n for n, _ in dom.plots]
    for e in expected_plots:
        check(e in names, f"{name}: plot '{e}' missing from the DOM (has {names})")
    for n, src in dom.plots:
        ok = src.startswith("data:image/svg+xml;base64,")
        if check(ok, f"{name}: plot '{n}' is not an embedded SVG"):
            svg = base64.b64decode(src.split(",", 1)[1]).decode("utf-8", "replace")
            check("<svg" in svg and ("<path" in svg or "<polyline" in svg), f"{name}: plot '{n}' draws nothing")
    check(dom.scripts == 0, f"{name}: {dom.scripts} <script> elements")
    check(not dom.urls, f"{name}: addresses in the page: {dom.urls[:3]}")
    page_requests = [u for u in urls if not BROWSER_HOSTS.match(u)]
    check(not page_requests, f"{name}: requests from the page: {page_requests[:3]}")
    check(not console, f"{name}: console messages (a refused or failed load): {console[:2]}")
    wrong = []
    for path, text in dom.numbers:
        try:
            value = pointer(report, path)
        except (KeyError, IndexError, ValueError, TypeError):
            wrong.append(f"{path}: not in the report")
            continue
        if not isinstance(value, (int, float)) or isinstance(value, bool) or printed(value) != text:
            wrong.append(f"{path}: page {text}, report {value}")
    check(len(dom.numbers) >= 20, f"{name}: only {len(dom.numbers)} numbers carry their JSON pointer")
    check(not wrong, f"{name}: numbers that are not the report's: {wrong[:3]}")
    print(f"{name}: {len(dom.plots)} plots, {len(dom.numbers)} numbers checked against the report, "
          f"{len(page_requests)} requests, screenshot {name}.png")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--dyncal", required=True)
    ap.add_argument("--source-dir", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    src, out, dyncal = a.source_dir, a.out, a.dyncal
    tx40 = os.path.join(src, "tests", "data", "staubli_tx40")
    gates = os.path.join(src, "tests", "data", "gates")
    o = lambda name: os.path.join(out, name)  # noqa: E731

    # identify: the TX40 example with the station's gate (passes) and the page.
    p = run([dyncal, "identify", "--format", "tx40", "--data", tx40, "--method", "pcls", "--report", o("identify.json"),
             "--html", o("identify.html"), "--params", o("tx40.params.json"), "--gate",
             os.path.join(gates, "tx40_station.yaml")], 0)
    check("gate: passed" in p.stdout, "identify: the station gate did not pass")
    check_page("identify", o("identify.html"), o("identify.json"),
               [f"torque_joint{j}" for j in range(1, 7)] + [f"residual_joint{j}" for j in range(1, 7)]
               + ["parameters_against_cad"], out)
    # The strict gate fails: exit 1, the failed items on stdout and in the report.
    p = run([dyncal, "identify", "--format", "tx40", "--data", tx40, "--method", "pcls", "--report", o("strict.json"),
             "--gate", os.path.join(gates, "tx40_strict.yaml")], 1)
    check("gate: FAILED" in p.stdout, "identify: the strict gate did not fail")
    with open(o("strict.json")) as f:
        gate = json.load(f)["gate"]
    failed = [i for i in gate["items"] if not i["passed"]]
    check(not gate["passed"] and failed, "strict gate: the report's gate does not fail")
    for i in failed:
        check(f"failed: {i['key']}: {i['what']}" in p.stdout, f"strict gate: '{i['what']}' not named on stdout")

    # predict and monitor: the same log with the parameter file identify wrote.
    run([dyncal, "predict", "--format", "tx40", "--data", tx40, "--params", o("tx40.params.json"), "--report",
         o("predict.json"), "--html", o("predict.html")], 0)
    check_page("predict", o("predict.html"), o("predict.json"), ["torque_joint1", "residual_joint6"], out)
    run([dyncal, "monitor", "--format", "tx40", "--data", tx40, "--params", o("tx40.params.json"), "--report",
         o("monitor.json"), "--html", o("monitor.html")], 0)
    check_page("monitor", o("monitor.html"), o("monitor.json"), [f"monitor_joint{j}" for j in range(1, 7)], out)

    # diagnose: a hidden case (a Stribeck effect on joint 1 of arm6), generated as the hidden-case
    # test generates it.
    logs = o("hidden")
    subprocess.run([sys.executable, os.path.join(src, "tests", "hidden_cases", "generate_logs.py"), "--source-dir", src,
                    "--out", logs], check=True, capture_output=True)
    run([dyncal, "diagnose", "--robots-dir", os.path.join(src, "tests", "robots"), "--robot", "arm6", "--data",
         os.path.join(logs, "arm6_t2_4_stribeck_1.csv"), "--model", "eq7", "--report", o("diagnose.json"), "--html",
         o("diagnose.html")], 0)
    check_page("diagnose", o("diagnose.html"), o("diagnose.json"),
               ["diagnose_before_after"] + [f"torque_joint{j}" for j in range(1, 7)], out)
    # diagnose on the TX40 log: beyond its catalogue it finds shapes in t (effects 3 and 4, joints 6
    # and 2), each drawn from the report's curve.
    run([dyncal, "diagnose", "--format", "tx40", "--data", tx40, "--friction-per-joint", "--report",
         o("diagnose_tx40.json"), "--html", o("diagnose_tx40.html")], 0)
    with open(o("diagnose_tx40.json")) as f:
        shapes = [f"shape_effect{i + 1}" for i, e in enumerate(json.load(f)["effects"]) if e["kind"] == "shape"]
    check(len(shapes) >= 1, f"diagnose_tx40: no shape found (effects: {shapes})")
    check_page("diagnose_tx40", o("diagnose_tx40.html"), o("diagnose_tx40.json"), ["diagnose_before_after"] + shapes,
               out)
    # identify with that diagnosis's effects: the shapes are model terms, each drawn from its fit.
    run([dyncal, "identify", "--format", "tx40", "--data", tx40, "--friction-per-joint", "--effects",
         o("diagnose_tx40.json"), "--report", o("identify_shapes.json"), "--html", o("identify_shapes.html")], 0)
    with open(o("identify_shapes.json")) as f:
        fitted = [f"shape_effect{i + 1}" for i, _ in enumerate(json.load(f).get("shapes", []))]
    check(len(fitted) == len(shapes), f"identify --effects: {len(fitted)} shapes fitted, the diagnosis found {len(shapes)}")
    check_page("identify_shapes", o("identify_shapes.html"), o("identify_shapes.json"), fitted, out)

    # calibrate on the simulated er20 drive, and payload on a second drive whose arm carries 2 kg.
    load = o("load_scenario.json")
    with open(load, "w") as f:
        json.dump({"payload": {"mass": 2.0, "com": [0.01, 0.0, 0.05],
                               "inertia_about_com": [0.004, 0.0, 0.0, 0.004, 0.0, 0.003]}}, f)
    drives = []
    try:
        uris = []
        for name, extra in (("plain", []), ("loaded", ["--scenario", load])):
            drive, uri = lockstep_drive.start(dyncal, out, name, extra)
            drives.append(drive)
            uris.append(uri)
        run([dyncal, "calibrate", "--drive", uris[0], "--quiet", "--save-log", o("unloaded.csv"), "--report",
             o("calibrate.json"), "--html", o("calibrate.html")], 0)
        check_page("calibrate", o("calibrate.html"), o("calibrate.json"),
                   ["parameters_against_cad", "torque_joint1", "residual_joint6"], out)
        run([dyncal, "calibrate", "--drive", uris[1], "--quiet", "--no-flash", "--save-log", o("loaded.csv")], 0)
    finally:
        for d in drives:
            lockstep_drive.stop(d)
    run([dyncal, "identify", "--robot", "er20", "--data", o("unloaded.csv"), "--params", o("arm.json")], 0)
    p = run([dyncal, "payload", "--robot", "er20", "--data", o("loaded.csv"), "--params", o("arm.json"), "--report",
             o("payload.json"), "--html", o("payload.html"), "--require", "payload_mass_min=1.9", "--require",
             "payload_mass_max=2.1"], 0)
    check("gate: passed" in p.stdout, "payload: a gate around the true mass did not pass")
    check_page("payload", o("payload.html"), o("payload.json"), [], out)
    p = run([dyncal, "payload", "--robot", "er20", "--data", o("loaded.csv"), "--params", o("arm.json"),
             "--require", "payload_mass_min=2.5"], 1)
    check("failed: payload_mass_min: payload mass" in p.stdout, "payload: a gate excluding the mass did not fail")

    for f in failures:
        print("FAILED: " + f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
