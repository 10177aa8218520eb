#!/usr/bin/env python3
"""Runs docs/python.md's example with the built module and checks it against the dyncal program.

- the bound functions (read_log, fit, ParameterSet, predict_log) give identify's and predict's figures,
  bit for bit;

- every identified parameter and standard deviation equals `dyncal identify`'s with the same
  options, bit for bit;
- the regressor times the base parameters equals the generated inverse dynamics (Newton-Euler,
  not through the regressor) on every sample, to 1e-9 of max(1, |tau|);
- the refused input raises dyncal.InputError with the CLI's message;
- predict, with the parameters identify saved, returns the CLI's report document.

usage: check_python_doc.py SOURCE_DIR MODULE_DIR DYNCAL_BINARY
"""
import contextlib
import io
import json
import os
import re
import subprocess
import sys
import tempfile


def to_lists(x):
    """The module's result as JSON values (numpy arrays as lists)."""
    if isinstance(x, dict):
        return {k: to_lists(v) for k, v in x.items()}
    if isinstance(x, list):
        return [to_lists(v) for v in x]
    if hasattr(x, "tolist"):
        return x.tolist()
    return x


def main():
    source, module_dir, binary = sys.argv[1:4]
    sys.path.insert(0, module_dir)
    os.chdir(source)
    doc = open(os.path.join(source, "docs", "python.md")).read()
    blocks = re.findall(r"```python\n(.*?)```", doc, re.S)
    if len(blocks) != 1:
        sys.exit(f"docs/python.md: expected one python example, found {len(blocks)}")
    scope = {}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(blocks[0], "docs/python.md", "exec"), scope)
    print(out.getvalue(), end="")
    failures = []

    # The CLI with the same options.
    with tempfile.TemporaryDirectory() as tmp:
        report = os.path.join(tmp, "cli.json")
        subprocess.run([binary, "identify", "--format", "tx40", "--data", "tests/data/staubli_tx40", "--model",
                        "eq7,rotor_inertia,offset", "--report", report], check=True, stdout=subprocess.DEVNULL)
        cli = json.load(open(report))
        refused = subprocess.run([binary, "identify", "--robot", "tx40", "--data", "no_such_log.csv"],
                                 capture_output=True, text=True)
    got = scope["result"]
    if len(got["params"]) != len(cli["params"]):
        failures.append(f"{len(got['params'])} parameters, the CLI {len(cli['params'])}")
    for a, b in zip(got["params"], cli["params"]):
        for key in ("name", "value", "std"):
            if a[key] != b[key]:
                failures.append(f"{b['name']} {key}: python {a[key]!r}, CLI {b[key]!r}")
    for a, b in zip(got["joints"], cli["joints"]):
        if a["r2_validation"] != b["r2_validation"]:
            failures.append(f"joint {b['joint']} r2_validation: python {a['r2_validation']!r}, CLI {b['r2_validation']!r}")
    if "Ia5 =" not in out.getvalue():
        failures.append("the example printed no Ia5")

    # Another command through the module: predict with the parameters identify saved, against the CLI's.
    dyncal = scope["dyncal"]
    with tempfile.TemporaryDirectory() as tmp:
        params = os.path.join(tmp, "p.json")
        dyncal.identify(format="tx40", data="tests/data/staubli_tx40", model="eq7,rotor_inertia,offset",
                        params=params)
        predicted = dyncal.predict(params=params, format="tx40", data="tests/data/staubli_tx40")
        report = os.path.join(tmp, "predict.json")
        subprocess.run([binary, "predict", "--params", params, "--format", "tx40", "--data", "tests/data/staubli_tx40",
                        "--report", report], check=True, stdout=subprocess.DEVNULL)
        cli_predicted = json.load(open(report))
    # The same document but for the command line each was given (the module's: the equivalent command).
    check_line = predicted.get("command_line", "").startswith("dyncal predict --params")
    if not check_line:
        failures.append(f"predict: the module's command_line is {predicted.get('command_line')!r}")
    if json.dumps({**to_lists(predicted), "command_line": ""}, sort_keys=True) != json.dumps(
            {**cli_predicted, "report_text": predicted["report_text"], "command_line": ""}, sort_keys=True):
        failures.append("predict: the module's document differs from the CLI's")

    # The library's functions bound directly (no command line): the same fit and prediction, bit for bit.
    tx40 = dyncal.Robot("tx40")
    log = dyncal.read_log(tx40, "tests/data/staubli_tx40", format="tx40")
    fit = dyncal.fit(tx40, log, model="eq7,rotor_inertia,offset")
    if list(fit.names) != [p["name"] for p in cli["params"]]:
        failures.append("fit: its parameter names are not the CLI's")
    for name, value, std, b in zip(fit.names, fit.values, fit.std, cli["params"]):
        std = None if std != std else float(std)  # the report's null: not determined
        if float(value) != b["value"] or std != b["std"]:
            failures.append(f"fit {name}: python {value!r} +- {std!r}, CLI {b['value']!r} +- {b['std']!r}")
    cli_bases = [p.get("basis", "") for p in cli["params"]]
    if list(fit.bases) != cli_bases:
        failures.append(f"fit: bases {list(fit.bases)!r}, the CLI's {cli_bases!r}")
    for j, b in enumerate(cli["joints"]):
        if float(fit.joints["r2"][j]) != b["r2_validation"]:
            failures.append(f"fit joint {j + 1} r2: python {fit.joints['r2'][j]!r}, CLI {b['r2_validation']!r}")
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "fit.json")
        fit.parameter_set().write(path)
        back = dyncal.ParameterSet.read(path)
        if list(back.values) != list(fit.values) or list(back.names) != list(fit.names):
            failures.append("ParameterSet: the file written does not read back as the fit")
        bound = dyncal.predict_log(tx40, log, back)
    for j, b in enumerate(cli_predicted["joints"]):
        if float(bound["rms"][j]) != b["rms_validation"]:
            failures.append(f"predict_log joint {j + 1} rms: python {bound['rms'][j]!r}, CLI {b['rms_validation']!r}")

    # Y_b phi_b against the generated Newton-Euler.
    robot, q, qd, qdd, tau, phi = (scope[k] for k in ("robot", "q", "qd", "qdd", "tau", "phi_b"))
    if scope["Y"].shape != (100, robot.joints, len(robot.base_parameter_names)):
        failures.append(f"Y has shape {scope['Y'].shape}")
    worst = 0.0
    for k in range(q.shape[0]):
        ref = robot.inverse_dynamics(q[k], qd[k], qdd[k], robot.nominal_standard)
        worst = max(worst, max(abs(ref - tau[k]) / max(1.0, abs(ref).max())))
    if not worst < 1e-9:
        failures.append(f"Y_b phi_b differs from the inverse dynamics by {worst:.3g}")
    one = robot.regressor(q[0], qd[0], qdd[0])
    if one.shape != (robot.joints, len(robot.base_parameter_names)) or abs(one - scope["Y"][0]).max() != 0:
        failures.append("one sample's regressor is not the batch's first")

    # The refused input: the CLI's one line.
    line = refused.stderr.strip()
    expected = line.removeprefix("dyncal: error: ")
    if refused.returncode != 2 or f"refused: {expected}" not in out.getvalue():
        failures.append(f"refusal: the CLI said {line!r} (exit {refused.returncode}), the example printed "
                        f"{out.getvalue().splitlines()[-1]!r}")
    if failures:
        print("\n".join("FAIL: " + f for f in failures))
        sys.exit(1)
    print(f"python_doc_example: {len(cli['params'])} parameters equal the CLI's; Y_b phi_b = ID to {worst:.2g}")


if __name__ == "__main__":
    main()
