"""The identified model as an MJCF file for MuJoCo (dyncal export mjcf, docs/export.md).

The arm is the robot's chain as dyncal compiles it (description.py: joint i is a fixed transform
[R p] followed by a rotation about or a translation along its own z): one MJCF <body> per joint at
pos = p, quat = R in its parent body, a hinge (revolute) or slide (prismatic) joint about or along z
at the body's origin, and the identified body as an <inertial> (mass, centre of mass, principal
moments and axes of the inertia about it; body frame). Per joint, what MuJoCo's joint holds:
armature = rotor inertia reflected to the joint (Ia, kg m^2; kg for a slide), damping = viscous
friction (Fv, N m s/rad; N s/m), frictionloss = Coulomb friction (Fc, Nm; N) (MuJoCo XML reference,
<joint>). Every other identified term (offsets, Stribeck, couplings, effects, terms acting through a coupled
transmission) has no place in a MuJoCo joint: it is kept as <custom><numeric name="dyncal_NAME">
and named in a comment. The file carries dynamics only: no geometry (no <geom>), so no contacts.
"""
import math
import os
import xml.etree.ElementTree as ET

import numpy as np

from . import description
from .urdf_export import lumped_links

FORMAT_VERSION = 1


def _fmt(v):
    return repr(float(v) + 0.0)


def quaternion(R):
    """(w, x, y, z) of the rotation matrix R (3x3 numpy), w >= 0 (Shepperd's method)."""
    t = np.trace(R)
    if t > 0:
        s = 2.0 * math.sqrt(1.0 + t)
        q = [0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    else:
        i = int(np.argmax(np.diag(R)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(1.0 + R[i, i] - R[j, j] - R[k, k])
        q = [0.0] * 4
        q[0] = (R[k, j] - R[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (R[j, i] + R[i, j]) / s
        q[1 + k] = (R[k, i] + R[i, k]) / s
    q = np.array(q)
    q /= np.linalg.norm(q)
    return q if q[0] >= 0 else -q


def principal_axes(c):
    """Principal moments and axes (columns, a rotation) of the inertia about the centre of mass c =
    [I11 I12 I13 I22 I23 I33]. Written as MJCF's diaginertia + quat: MuJoCo would otherwise
    diagonalise a fullinertia itself with its own iterative method, less exactly than LAPACK."""
    I = np.array([[c[0], c[1], c[2]], [c[1], c[3], c[4]], [c[2], c[4], c[5]]], dtype=float)
    moments, axes = np.linalg.eigh(I)
    if np.linalg.det(axes) < 0:
        axes[:, 2] = -axes[:, 2]
    return moments, axes


def body_names(robot_dir, desc, n):
    """The moving child link of each joint in the maker's URDF when the robot was imported from one,
    else link_1 .. link_n."""
    src = desc.get("source")
    if isinstance(src, dict) and "file" in src:
        bodies = lumped_links(os.path.join(robot_dir, src["file"]), src.get("base"), src.get("tip"))
        if len(bodies) == n:
            return [b["child"] for b in bodies]
    return [f"link_{i + 1}" for i in range(n)]


def export(robot_dir, model):
    """The MJCF text of the robot in `robot_dir` with `model`'s values: model = {links: per joint
    {mass, com[3], inertia_about_com[6] (I11 I12 I13 I22 I23 I33)}, joints: per joint {armature,
    damping, frictionloss}, not_held: [{name, value, why}], provenance: {params, robot, model}}.
    Raises description.DescriptionError: a description that does not load, counts that differ."""
    desc, joints = description.load(robot_dir)
    n = len(joints)
    if len(model["links"]) != n or len(model["joints"]) != n:
        raise description.DescriptionError(f"{len(model['links'])} links and {len(model['joints'])} joints for a "
                                           f"chain of {n}")
    names = body_names(robot_dir, desc, n)
    limits = desc["limits"]
    prov = model["provenance"]
    root = ET.Element("mujoco", {"model": desc["name"]})
    root.append(ET.Comment(
        f" dyncal export mjcf (format {FORMAT_VERSION}) from {prov.get('params', '?')} "
        f"(robot {prov.get('robot', '?')}, "
        f"model {prov.get('model', '?')}): identified inertials; joint armature = rotor inertia Ia, damping = Fv, "
        "frictionloss = Fc; dynamics only, no geometry (docs/export.md) "))
    ET.SubElement(root, "compiler", {"angle": "radian", "inertiafromgeom": "false"})
    ET.SubElement(root, "option", {"gravity": " ".join(_fmt(g) for g in desc["gravity"])})
    parent = ET.SubElement(root, "worldbody")
    for i, (j, link, terms) in enumerate(zip(joints, model["links"], model["joints"])):
        R = np.array(j.R.evalf(), dtype=float)
        p = np.array(j.p.evalf(), dtype=float).reshape(3)
        body = ET.SubElement(parent, "body",
                             {"name": names[i], "pos": " ".join(_fmt(v) for v in p),
                              "quat": " ".join(_fmt(v) for v in quaternion(R))})
        ET.SubElement(body, "joint",
                      {"name": j.name, "type": "slide" if j.kind == description.PRISMATIC else "hinge", "axis": "0 0 1",
                       "limited": "true",
                       "range": f"{_fmt(limits['q_min'][i])} {_fmt(limits['q_max'][i])}",
                       "armature": _fmt(terms["armature"]), "damping": _fmt(terms["damping"]),
                       "frictionloss": _fmt(terms["frictionloss"])})
        moments, axes = principal_axes(link["inertia_about_com"])
        ET.SubElement(body, "inertial",
                      {"pos": " ".join(_fmt(v) for v in link["com"]), "mass": _fmt(link["mass"]),
                       "quat": " ".join(_fmt(v) for v in quaternion(axes)),
                       "diaginertia": " ".join(_fmt(v) for v in moments)})
        parent = body
    if model["not_held"]:
        custom = ET.SubElement(root, "custom")
        custom.append(ET.Comment(" identified terms a MuJoCo joint cannot hold: "
                                 + "; ".join(f"{t['name']} ({t['why']})" for t in model["not_held"]) + " "))
        for t in model["not_held"]:
            ET.SubElement(custom, "numeric", {"name": "dyncal_" + t["name"], "data": _fmt(t["value"])})
    ET.indent(root, space="  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
