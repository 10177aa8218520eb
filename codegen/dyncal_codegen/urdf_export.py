"""The identified model written back into the URDF a robot was imported from (dyncal export urdf,
docs/export.md).

Import merged each moving joint's child link with the links fixed to it (and, past the tip, a flange
or tool) into one body, expressed in a frame whose z is the joint axis. Export undoes that frame
change: each body's identified inertial (mass, centre of mass, inertia about it; the normalised
frame) is written, in the moving child link's own URDF frame, into that link, and the links import
merged into it lose their <inertial> (their mass is in the body: no data can split it again). Every
other element of the file is kept as it was. Coulomb and viscous friction go into the joint's
standard <dynamics friction= damping=>; the other identified terms (rotor inertia, offsets, effects)
into a <dyncal> element (URDF readers ignore unknown elements).
"""
import re
import xml.etree.ElementTree as ET

import numpy as np

from .urdf_import import ImportError_, Inertial, _path, normalise, parse, transform

FORMAT_VERSION = 1


def _fmt(v):
    return repr(float(v) + 0.0)


def lumped_links(path, base, tip):
    """Per moving joint of the chain: (its child link, the other URDF links import merged into its
    body), in chain order, as urdf_import.normalise walks the path."""
    _, _, joints = parse(path)
    children, parent_joint = {}, {}
    for j in joints:
        children.setdefault(j.parent, []).append(j)
        parent_joint[j.child] = j
    path_joints = _path(base, tip, parent_joint, children)
    bodies, current, link = [], None, base

    def subtree(name, skip):
        out = [name]
        for j in children.get(name, []):
            if j.child != skip:
                out += subtree(j.child, None)
        return out

    for j in path_joints:
        if current is not None:
            current["merged"] += subtree(link, j.child)
        if j.moves:
            current = {"joint": j.name, "child": j.child, "merged": []}
            bodies.append(current)
        link = j.child
    current["merged"] += subtree(link, None)
    for b in bodies:
        b["merged"] = [name for name in b["merged"] if name != b["child"]]
    return bodies


def _inertial_element(body, indent):
    """An <inertial> of `body` (mass, com, inertia about com; the link's frame)."""
    I = body.inertia
    el = ET.Element("inertial")
    el.text = "\n" + indent + "  "
    origin = ET.SubElement(el, "origin", {"xyz": " ".join(_fmt(v) for v in body.com), "rpy": "0 0 0"})
    origin.tail = "\n" + indent + "  "
    mass = ET.SubElement(el, "mass", {"value": _fmt(body.mass)})
    mass.tail = "\n" + indent + "  "
    inertia = ET.SubElement(el, "inertia", {"ixx": _fmt(I[0, 0]), "ixy": _fmt(I[0, 1]), "ixz": _fmt(I[0, 2]),
                                            "iyy": _fmt(I[1, 1]), "iyz": _fmt(I[1, 2]), "izz": _fmt(I[2, 2])})
    inertia.tail = "\n" + indent
    return el


def _replace_child(parent, tag, new, indent):
    old = parent.find(tag)
    if old is not None:
        new.tail = old.tail
        parent[list(parent).index(old)] = new
    else:
        if len(parent) == 0:
            parent.text = "\n" + indent + "  "
            new.tail = "\n" + indent
        else:
            parent[-1].tail = "\n" + indent + "  "
            new.tail = "\n" + indent
        parent.append(new)


def _joint_terms(terms, n):
    """Per joint (0-based) the identified terms named NAME<joint> (Fc3, Ia3, offset3, ...), and the
    terms of no single joint."""
    per_joint = [dict() for _ in range(n)]
    other = []
    for t in terms:
        m = re.fullmatch(r"([A-Za-z_]+?)(\d+)", t["name"])
        if m and 1 <= int(m.group(2)) <= n:
            per_joint[int(m.group(2)) - 1][m.group(1)] = float(t["value"])
        else:
            other.append(t)
    return per_joint, other


def export(source, base, tip, chain_names, links, terms, provenance):
    """The ElementTree of `source` with the identified inertials and terms. links: per chain joint
    {mass, com[3], inertia_about_com[6]} in the normalised body frame; terms: [{name, value}];
    provenance: attributes of the <dyncal> element."""
    _, chain = normalise(source, base, tip)
    if [j["name"] for j in chain.joints] != list(chain_names):
        raise ImportError_(f"{source}: its chain ({', '.join(j['name'] for j in chain.joints)}) is not the robot's "
                           f"({', '.join(chain_names)}): re-import it")
    if len(links) != len(chain.joints):
        raise ImportError_(f"{len(links)} link inertials for a chain of {len(chain.joints)} joints")
    tree = ET.parse(source, parser=ET.XMLParser(target=ET.TreeBuilder(insert_comments=True)))
    root = tree.getroot()
    by_name = {el.get("name"): el for el in root.findall("link")}
    joints_by_name = {el.get("name"): el for el in root.findall("joint")}
    bodies = lumped_links(source, base, tip)
    for k, (j, b, l) in enumerate(zip(chain.joints, bodies, links)):
        c = l["inertia_about_com"]
        inertia = np.array([[c[0], c[1], c[2]], [c[1], c[3], c[4]], [c[2], c[4], c[5]]], dtype=float)
        body = Inertial(float(l["mass"]), np.array(l["com"], dtype=float), inertia)
        in_link = body.moved(transform(j["A"], np.zeros(3)))  # body frame -> the child link's URDF frame
        link_el = by_name[b["child"]]
        inertial = _inertial_element(in_link, "    ")
        if l.get("mass_basis"):  # identify's interval, and a mark on what neither data nor prior fix
            mark = "NOT DETERMINED, written as forced: " if l.get("not_determined") else ""
            std = _fmt(float(l["mass_std"])) if l.get("mass_std") is not None else "(no interval)"
            basis = f", from the {l['mass_basis']}" if l["mass_basis"] in ("data", "prior") else ""
            note = ET.Comment(f" dyncal: {mark}mass {_fmt(float(l['mass']))} +- {std} kg (std){basis} ")
            note.tail = "\n      "
            inertial.insert(0, note)
        _replace_child(link_el, "inertial", inertial, "  ")
        for name in b["merged"]:
            el = by_name[name]
            old = el.find("inertial")
            if old is not None:
                el.remove(old)
                el.append(ET.Comment(f" inertial merged into link '{b['child']}' by dyncal export "))
    per_joint, other = _joint_terms(terms, len(chain.joints))
    ext = ET.Element("dyncal", {k: str(v) for k, v in provenance.items()})
    ext.set("version", str(FORMAT_VERSION))
    ext.text = "\n    "
    items = []
    for k, j in enumerate(chain.joints):
        t = per_joint[k]
        joint_el = joints_by_name[j["name"]]
        if "Fc" in t or "Fv" in t:
            dyn = ET.Element("dynamics", {"damping": _fmt(t.get("Fv", 0.0)), "friction": _fmt(t.get("Fc", 0.0))})
            _replace_child(joint_el, "dynamics", dyn, "  ")
        rest = {name: v for name, v in t.items() if name not in ("Fc", "Fv")}
        if rest:
            items.append(ET.Element("joint", {"name": j["name"], **{name: _fmt(v) for name, v in rest.items()}}))
    for t in other:
        items.append(ET.Element("term", {"name": t["name"], "value": _fmt(t["value"])}))
    for i, el in enumerate(items):
        el.tail = "\n    " if i + 1 < len(items) else "\n  "
        ext.append(el)
    if not items:
        ext.text = None
    if len(root):
        root[-1].tail = "\n  "
    ext.tail = "\n"
    root.append(ext)
    return tree, chain


def to_text(source, tree, provenance):
    """The written file: the source's prolog (XML declaration, comments before <robot>) kept, a
    comment saying what export changed, then the edited tree."""
    with open(source, encoding="utf-8") as f:
        text = f.read()
    start = text.find("<robot")
    prolog = text[:start] if start >= 0 else '<?xml version="1.0"?>\n'
    if not prolog.endswith("\n"):
        prolog += "\n"
    note = (f"<!-- dyncal export urdf: link inertials, joint <dynamics> and the <dyncal> element written from "
            f"{provenance.get('params', '?')} (robot {provenance.get('robot', '?')}, model "
            f"{provenance.get('model', '?')}); the rest as in the source. Inertials the log did not determine "
            f"keep the identification's prior (docs/export.md). -->\n")
    return prolog + note + ET.tostring(tree.getroot(), encoding="unicode") + "\n"
