#!/usr/bin/env python3
"""Issue 67 from Python: the module refuses what the CLI refuses, with the CLI's line.

- identify(help=True) returns the command's help text (it raised "This should be caught in your
  main function");
- dyncal.Robot runs the CLI's one description check: an MDH robot whose link was edited since the
  build is refused, naming the field (it was taken, with the compiled values);
- an output that is not a regular file (a FIFO) is refused before any work, and stays a FIFO;
- issue 72: set_progress(callback) receives identify's progress, None keeps it quiet; a failed gate
  returns the report with its failed items instead of raising.

usage: python_input_cases.py SOURCE_DIR MODULE_DIR
"""
import json
import os
import shutil
import sys
import tempfile

SRC, MODULE_DIR = sys.argv[1], sys.argv[2]
sys.path.insert(0, MODULE_DIR)
import dyncal  # noqa: E402

failures = []


def check(what, ok, detail=""):
    print(f"{'ok  ' if ok else 'FAIL'} {what}{': ' + detail if detail else ''}")
    if not ok:
        failures.append(what)


help_doc = dyncal.identify(help=True)
check("identify(help=True) returns the help text", "--data" in help_doc.get("help", ""), str(help_doc)[:80])

with tempfile.TemporaryDirectory() as tmp:
    robots = os.path.join(tmp, "robots")
    shutil.copytree(os.path.join(SRC, "robots", "er20"), os.path.join(robots, "er20"))
    path = os.path.join(robots, "er20", "robot.json")
    with open(path) as f:
        desc = json.load(f)
    desc["links"][1]["mass"] = 41.0
    with open(path, "w") as f:
        json.dump(desc, f)
    try:
        dyncal.Robot("er20", robots)
        check("an edited MDH link is refused", False, "accepted")
    except dyncal.InputError as e:
        check("an edited MDH link is refused", "links[2].mass 41 differs from the compiled model's 40" in str(e), str(e))

    fifo = os.path.join(tmp, "fifo")
    os.mkfifo(fifo)
    try:
        dyncal.identify(robot="er20", data=os.path.join(tmp, "none.csv"), params=fifo)
        check("a FIFO as params is refused", False, "accepted")
    except dyncal.InputError as e:
        check("a FIFO as params is refused", "not a regular file" in str(e), str(e))
    check("the FIFO stays a FIFO", os.path.exists(fifo) and not os.path.isfile(fifo))

# Issue 72: progress through a callback (quiet without one), a failed gate as a report, not an error.
updates = []
dyncal.set_progress(lambda task, done, total, finished: updates.append((task, done, total, finished)))
tx40 = os.path.join(SRC, "tests", "data", "staubli_tx40")
doc = dyncal.identify(format="tx40", data=tx40, require=["r2_validation_min=0.999"])
dyncal.set_progress(None)
check("identify reports its folds to the progress callback",
      any(t.startswith("identify:") and f for t, _, _, f in updates) and len(updates) >= 3, str(updates[:3]))
check("a failed gate returns the report with its items",
      doc.get("gate", {}).get("passed") is False and any(not i["passed"] for i in doc["gate"]["items"]),
      str(doc.get("gate", {}))[:120])
quiet = dyncal.identify(format="tx40", data=tx40)
check("without a callback identify stays quiet", "\r" not in quiet["report_text"] and "gate" not in quiet)

if failures:
    print(f"{len(failures)} failed: {failures}")
    sys.exit(1)
print("all passed")
