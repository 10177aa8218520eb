#!/usr/bin/python3
"""Bad input for `dyncal robot import`, `dyncal robot check` and the C++ robot.json loader: every
malformed URDF and robot.json of the tables below must give exactly one line on stderr naming the
problem, no traceback, and exit 2; nothing may be written for a refused import. Also: re-importing
the test URDFs reproduces the committed tests/robots/ folders byte for byte.

Usage: robot_input_cases.py DYNCAL SOURCE_DIR"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

DYNCAL, SRC = sys.argv[1], sys.argv[2]
ARM3 = open(os.path.join(SRC, "tests/urdf/arm3.urdf")).read()
failures = []


def run(args):
    p = subprocess.run([DYNCAL] + args, capture_output=True, text=True, errors="replace")
    return p.returncode, p.stdout, p.stderr


def expect_one_line(case, args, needle):
    rc, out, err = run(args)
    lines = [line for line in err.splitlines() if line.strip()]
    ok = rc == 2 and len(lines) == 1 and "Traceback" not in err and needle in err and "\ufffd" not in err and \
        all(c.isprintable() for c in err.strip())
    print(f"{'ok  ' if ok else 'FAIL'} {case}: exit {rc}: {err.strip()}")
    if not ok:
        failures.append(f"{case}: expected exit 2 and one line containing {needle!r}; got exit {rc}, stderr {err!r}")


def urdf_case(tmp, case, text, needle, extra=()):
    path = os.path.join(tmp, case + ".urdf")
    with open(path, "w") as f:
        f.write(text)
    robots = os.path.join(tmp, "robots_" + case)
    expect_one_line("urdf " + case, ["robot", "import", path, "--name", "arm", "--robots-dir", robots, *extra], needle)
    if os.path.exists(os.path.join(robots, "arm")):
        failures.append(f"urdf {case}: the refused import wrote {robots}/arm")


def replace(old, new, count=1):
    assert old in ARM3, old
    return ARM3.replace(old, new, count)


ELBOW_LIMIT = '<limit lower="-2.5" upper="2.5" velocity="2.5" effort="60"/>'
URDF_CASES = [
    ("not_xml", "this is not a URDF <robot", "not a readable URDF"),
    ("not_robot", '<?xml version="1.0"?><model name="x"/>', "not <robot>"),
    ("planar", replace('name="elbow" type="revolute"', 'name="elbow" type="planar"'), "joint 'elbow' is planar"),
    ("mimic", replace(ELBOW_LIMIT, ELBOW_LIMIT + '<mimic joint="pitch"/>'), "joint 'elbow' is a mimic joint"),
    ("branching", replace("</robot>", '<joint name="wrist2" type="revolute"><parent link="upper_arm"/>'
                          '<child link="side"/><axis xyz="0 0 1"/>'
                          '<limit lower="-1" upper="1" velocity="1" effort="1"/></joint>'
                          '<link name="side"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" '
                          'iyy="0.01" iyz="0" izz="0.01"/></inertial></link></robot>'), "branches at link 'upper_arm'"),
    ("no_limit", replace(ELBOW_LIMIT, ""), "joint 'elbow'"),
    ("no_velocity", replace(ELBOW_LIMIT, '<limit lower="-2.5" upper="2.5" effort="60"/>'), "velocity"),
    ("upper_below_lower", replace(ELBOW_LIMIT, '<limit lower="2.5" upper="-2.5" velocity="2.5" effort="60"/>'),
     "is not above lower"),
    ("zero_axis", replace('<axis xyz="-1 0 0"/>', '<axis xyz="0 0 0"/>'), "zero axis"),
    ("bad_axis", replace('<axis xyz="-1 0 0"/>', '<axis xyz="-1 zero 0"/>'), "is not 3 numbers"),
    ("negative_mass", replace('<mass value="3.0"/>', '<mass value="-3.0"/>'), "negative mass"),
    ("undefined_link", replace('<child link="forearm"/>', '<child link="forarm"/>'), "is not defined"),
    ("two_parents", replace("</robot>", '<joint name="again" type="fixed"><parent link="shoulder"/>'
                            '<child link="forearm"/></joint></robot>'), "has two parent joints"),
]


def robot_json_cases(good):
    """(case, mutate(desc) -> desc or a raw string, needle) for a valid description `good`."""
    def edit(fn):
        def go(d):
            d = json.loads(json.dumps(d))
            fn(d)
            return d
        return go

    return [
        ("invalid_json", lambda d: "{ \"name\": ", "invalid JSON"),
        ("not_object", lambda d: "[1, 2]", "not a JSON object"),
        ("no_limits", edit(lambda d: d.pop("limits")), "limits"),
        ("no_qd_max", edit(lambda d: d["limits"].pop("qd_max")), "limits.qd_max"),
        ("short_q_max", edit(lambda d: d["limits"]["q_max"].pop()), "limits.q_max"),
        ("q_max_below_q_min", edit(lambda d: d["limits"]["q_max"].__setitem__(1, -5.0)), "limits.q_max[2]"),
        ("negative_qd_max", edit(lambda d: d["limits"]["qd_max"].__setitem__(0, -1.0)), "limits.qd_max[1]"),
        ("string_tau_max", edit(lambda d: d["limits"].__setitem__("tau_max", ["a", 1, 1])), "limits.tau_max[1]"),
        ("zero_tau_max", edit(lambda d: d["limits"].__setitem__("tau_max", [10, 0, 10])), "limits.tau_max[2]"),
        ("negative_tau_max", edit(lambda d: d["limits"].__setitem__("tau_max", [10, 10, -3])), "limits.tau_max[3]"),
        ("zero_gear", edit(lambda d: d.__setitem__("transmission", {"gear_ratios": [1, 0, 1]})),
         "transmission.gear_ratios[2]"),
        ("coupling_out_of_range", edit(lambda d: d.__setitem__(
            "transmission", {"gear_ratios": [1, 1, 1], "coupling": [{"motor": 4, "joint": 1, "ratio": 1}]})),
         "transmission.coupling[1].motor"),
        ("zero_torque_constant", edit(lambda d: d.__setitem__(
            "transmission", {"gear_ratios": [1, 1, 1], "torque_constants": [0.1, 0.1, 0]})),
         "transmission.torque_constants[3]"),
        ("short_torque_constants", edit(lambda d: d.__setitem__(
            "transmission", {"gear_ratios": [1, 1, 1], "torque_constants": [0.1, 0.1]})),
         "transmission.torque_constants"),
        ("name_differs", edit(lambda d: d.__setitem__("name", "other")), "name"),
        ("friction_not_object", edit(lambda d: d.__setitem__("friction", [1, 2, 3])), "friction[1]"),
        ("too_many_joints", edit(lambda d: [d["limits"][k].extend([1.0] * 5) for k in d["limits"]]),
         "limits"),
        ("nested_too_deeply", lambda d: "[" * 100000, "invalid JSON"),
        ("utf16", lambda d: json.dumps(d).encode("utf-16"), "robot.json"),
    ]


def main():
    with tempfile.TemporaryDirectory() as tmp:
        for case, text, needle in URDF_CASES:
            urdf_case(tmp, case, text, needle)
        expect_one_line("urdf missing file", ["robot", "import", os.path.join(tmp, "none.urdf"), "--name", "arm",
                                              "--robots-dir", tmp], "none.urdf")
        good = os.path.join(SRC, "tests/urdf/arm3.urdf")
        expect_one_line("bad --name", ["robot", "import", good, "--name", "3arm", "--robots-dir", tmp], "--name")
        expect_one_line("unknown --tip", ["robot", "import", good, "--name", "arm", "--tip", "hand",
                                          "--robots-dir", tmp], "'hand'")
        eight = ARM3
        for k in range(6):  # 3 + 6 moving joints
            eight = eight.replace("</robot>", f'<joint name="x{k}" type="revolute"><parent link="'
                                  f'{"forearm" if k == 0 else f"l{k - 1}"}"/><child link="l{k}"/><axis xyz="0 0 1"/>'
                                  '<limit lower="-1" upper="1" velocity="1" effort="1"/></joint>'
                                  f'<link name="l{k}"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" '
                                  'ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link></robot>')
        urdf_case(tmp, "nine_joints", eight, "1 to 7")

        # A moving joint past the chosen tip (a gripper's finger, issue 68) is taken rigid at its zero
        # position with a note, its link's mass in the last body; it was refused as "not on the chain".
        finger = ARM3.replace("</robot>", '<joint name="finger" type="prismatic"><parent link="forearm"/>'
                              '<child link="finger_link"/><origin xyz="0 0 0.3"/><axis xyz="1 0 0"/>'
                              '<limit lower="0" upper="0.04" velocity="0.1" effort="10"/></joint>'
                              '<link name="finger_link"><inertial><mass value="0.25"/><inertia ixx="1e-4" ixy="0" '
                              'ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link></robot>')
        path = os.path.join(tmp, "finger.urdf")
        with open(path, "w") as f:
            f.write(finger)
        rc, out, err = run(["robot", "import", path, "--name", "fingered", "--tip", "forearm", "--robots-dir",
                            os.path.join(tmp, "robots_finger")])
        noted = "1 joint past the tip 'forearm' (finger) taken rigid at zero position" in out
        print(f"{'ok  ' if rc == 0 and noted else 'FAIL'} a finger past --tip: exit {rc}: {out.strip()} {err.strip()}")
        if rc != 0 or not noted:
            failures.append(f"a finger past --tip: exit {rc}, stdout {out!r}, stderr {err!r}")

        # An existing robot is not replaced without --force.
        robots = os.path.join(tmp, "robots")
        rc, _, err = run(["robot", "import", good, "--name", "arm3", "--robots-dir", robots])
        if rc != 0:
            failures.append(f"importing arm3 failed: {err}")
        expect_one_line("existing robot", ["robot", "import", good, "--name", "arm3", "--robots-dir", robots], "--force")

        # Re-importing reproduces the committed test robots; of robot.json, what the import writes (the
        # fields a URDF holds nothing for, added by hand after it, docs/robots.md, are left out).
        hand_added = {"transmission", "friction", "joint_names", "log_formats"}
        for name in sorted(os.listdir(os.path.join(SRC, "tests/robots"))):
            out = os.path.join(tmp, "reimport")
            committed = os.path.join(SRC, "tests/robots", name)
            source = json.load(open(os.path.join(committed, "robot.json")))["source"]
            rc, _, err = run(["robot", "import", os.path.join(SRC, f"tests/urdf/{name}.urdf"), "--name", name,
                              "--base", source["base"], "--tip", source["tip"], "--robots-dir", out])
            for f in sorted(os.listdir(committed)):
                a, b = open(os.path.join(committed, f), "rb").read(), open(os.path.join(out, name, f), "rb").read()
                if f == "robot.json":
                    a_json, b_json = json.loads(a), json.loads(b)
                    extra = set(a_json) - set(b_json)
                    if not extra <= hand_added:
                        failures.append(f"re-import of {name}: robot.json has {sorted(extra - hand_added)} the import "
                                        "does not write")
                    a = json.dumps({k: v for k, v in a_json.items() if k not in hand_added}, indent=2).encode()
                    b = json.dumps(b_json, indent=2).encode()
                if a != b:
                    failures.append(f"re-import of {name}: {f} differs from tests/robots/{name}/{f}")
            print(f"ok   re-import of {name} equals tests/robots/{name}" if rc == 0 else f"FAIL {err}")

        # robot.json: the Python check and the C++ loader (excite reads it) refuse the same files.
        base = json.load(open(os.path.join(robots, "arm3", "robot.json")))
        for case, mutate, needle in robot_json_cases(base):
            d = os.path.join(tmp, "json_" + case)
            shutil.copytree(os.path.join(robots, "arm3"), os.path.join(d, "arm3"))
            desc = mutate(base)
            with open(os.path.join(d, "arm3", "robot.json"), "wb") as f:
                f.write(desc if isinstance(desc, bytes) else (desc if isinstance(desc, str) else json.dumps(desc)).encode())
            expect_one_line("robot.json " + case + " (check)", ["robot", "check", "arm3", "--robots-dir", d], needle)
            expect_one_line("robot.json " + case + " (C++ loader)",
                            ["excite", "--robot", "arm3", "--robots-dir", d, "--out", os.path.join(d, "t.json")],
                            needle)
        # The folder's URDF copy: an edited inertial, and one no link of the arm can have (issue 43).
        copy_text = open(os.path.join(robots, "arm3", "arm3.urdf")).read()
        for case, text, needle in [
                ("edited_mass", copy_text.replace('<mass value="5.0"/>', '<mass value="2.5"/>', 1), "was edited"),
                ("huge_inertia", copy_text.replace('ixx="', 'ixx="1e308" old="', 1), "twice the arm's extent")]:
            d = os.path.join(tmp, "urdf_copy_" + case)
            shutil.copytree(os.path.join(robots, "arm3"), os.path.join(d, "arm3"))
            assert text != copy_text, case
            with open(os.path.join(d, "arm3", "arm3.urdf"), "w") as f:
                f.write(text)
            expect_one_line("URDF copy " + case + " (check)", ["robot", "check", "arm3", "--robots-dir", d], needle)
        huge = ARM3.replace('ixx="', 'ixx="1e308" old="', 1)
        urdf_case(tmp, "huge_inertia", huge, "twice the arm's extent")
        d = os.path.join(tmp, "json_directory")
        os.makedirs(os.path.join(d, "arm3", "robot.json"))
        expect_one_line("robot.json is a directory (C++ loader)", ["excite", "--robot", "arm3", "--robots-dir", d,
                                                                   "--out", os.path.join(d, "t.json")], "not a regular file")
        expect_one_line("unknown robot", ["robot", "check", "nobody", "--robots-dir", d], "unknown robot 'nobody'")
    if failures:
        print("\n".join(failures), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
