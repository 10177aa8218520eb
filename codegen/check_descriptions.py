#!/usr/bin/python3
"""Checks that a robot's two descriptions (URDF and modified DH) describe the same arm.

Usage: check_descriptions.py ROBOT_DIR
robot.json's "kinematics" is the primary description, "alternate_kinematics" the other format.
Both are reduced to per-joint fixed transforms [R p] and standard parameters; they must agree to
1e-9 (joint transforms) and 1e-9 relative (standard parameters, where the alternate has them).
Exit 0 when they agree, 1 with the first difference otherwise.
"""
import copy
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from dyncal_codegen import description  # noqa: E402

TOLERANCE = 1e-9


def main():
    robot_dir = sys.argv[1]
    desc, primary = description.load(robot_dir)
    alt_desc = copy.deepcopy(desc)
    alt_desc["kinematics"] = desc["alternate_kinematics"]
    if alt_desc["kinematics"]["format"] == "mdh" and "links" not in alt_desc:
        # links of an MDH alternate come from the primary (same link frames)
        alt_desc["links"] = None
        alternate = description.load_mdh_kinematics(alt_desc)
    else:
        alternate = description.load_description(robot_dir, alt_desc)
    if len(primary) != len(alternate):
        print(f"{desc['name']}: {len(primary)} joints vs {len(alternate)}")
        return 1
    for i, (a, b) in enumerate(zip(primary, alternate)):
        dR = max(abs(float((a.R - b.R)[r, c].evalf())) for r in range(3) for c in range(3))
        dp = max(abs(float((a.p - b.p)[r].evalf())) for r in range(3))
        if dR > TOLERANCE or dp > TOLERANCE:
            print(f"{desc['name']}: joint {i + 1} transforms differ (|dR| {dR:.3g}, |dp| {dp:.3g})")
            return 1
        if b.standard is not None:
            scale = max(1.0, max(abs(x) for x in a.standard))
            d = max(abs(x - y) for x, y in zip(a.standard, b.standard))
            if d > TOLERANCE * scale:
                print(f"{desc['name']}: link {i + 1} standard parameters differ by {d:.3g}")
                return 1
    print(f"{desc['name']}: {desc['kinematics']['format']} and {alt_desc['kinematics']['format']} descriptions agree")
    return 0


if __name__ == "__main__":
    sys.exit(main())
