"""Semantic mutations of the model file, each with the answer the format promises
(docs/model-format.md, "Duplicates, sums and impossible physics"):

* an entry of a table that adds (a bearing, a force, a layer, a mesh, a transmission-error
  harmonic) written twice: the assembled mean mass, stiffness and load change by exactly
  what the entry contributes (``X(twice) - X(once) == X(once) - X(none)``);
* an entry that may not repeat (a name, a disk at one node, an element in a layer's set)
  or a value no body can have (inertias breaking ``I3 <= I1 + I2``, a single tooth pair
  stiffer than two, a negative stiffness or mass): refused, naming its field.

:func:`semantic_case` draws one; :func:`check_semantic` judges it (AssertionError when the
promise is broken: a silent overwrite, a doubled value, a silent acceptance).
"""

from __future__ import annotations

import copy
import tomllib
from typing import Any

import numpy as np
from hypothesis import strategies as st

from rheolin.data import example_text

#: Mutations whose promise is "adds", and those whose promise is "refused".
ADDS = ("bearing", "force", "layer", "mesh", "transmission_error")
REFUSED = (
    "bearing_name", "disk_node", "layer_elements", "inertia", "single_double",
    "negative_stiffness", "body_name", "negative_mass", "components", "speeds", "positions",
    "link",
)  # fmt: skip

LAYER = {"elements": [0], "outer_diameter": "44 mm", "inner_diameter": "30 mm",
         "elastic_modulus": "70 GPa", "poisson_ratio": 0.33, "density": "2700 kg/m^3"}  # fmt: skip
FORCE = {"name": "push", "body": "rotor", "node": 1, "force": ["0 N", "-50 N", "10 N"],
         "order": "1", "phase": "30 deg"}  # fmt: skip


def _doc(name: str) -> dict[str, Any]:
    doc = tomllib.loads(example_text(name))
    if name == "rotor":  # a layer and a force to write twice
        doc["shafts"][0]["layers"] = [dict(LAYER)]
        doc["forces"] = [dict(FORCE)]
    return doc


@st.composite
def semantic_case(draw: st.DrawFn) -> tuple[str, dict[str, Any], dict[str, Any] | None, Any]:
    """``(kind, twice, none, original)``: for an "adds" kind, the documents with the entry
    twice, without it, and once; for a "refused" kind, ``twice`` is the bad document,
    ``none`` None and ``original`` the field path the refusal must name."""
    kind = draw(st.sampled_from(ADDS + REFUSED))
    name = "gearbox" if kind in ("mesh", "transmission_error", "single_double") else "rotor"
    doc = _doc(name)
    once, twice, none = doc, copy.deepcopy(doc), copy.deepcopy(doc)
    if kind == "bearing":
        s = draw(st.sampled_from(range(len(doc["shafts"]))))
        i = draw(st.sampled_from(range(len(doc["shafts"][s]["bearings"]))))
        entry = copy.deepcopy(doc["shafts"][s]["bearings"][i])
        entry["name"] += "_again"
        twice["shafts"][s]["bearings"].append(entry)
        del none["shafts"][s]["bearings"][i]
    elif kind == "force":
        twice["forces"].append(dict(FORCE, name="push_again"))
        none["forces"] = []
    elif kind == "layer":
        twice["shafts"][0]["layers"].append(dict(LAYER))
        none["shafts"][0]["layers"] = []
    elif kind == "mesh":
        i = draw(st.sampled_from([0, 1]))
        entry = copy.deepcopy(doc["meshes"][i])
        entry["name"] += "_again"
        twice["meshes"].append(entry)
        del none["meshes"][i]["transmission_error"]  # the mesh itself stays (kinematics)
        none["meshes"][i]["stiffness"] = "0 N/m"
        for key in ("contact_ratio", "single_stiffness", "double_stiffness"):
            none["meshes"][i].pop(key, None)
        none["meshes"][i]["damping"] = "0 N*s/m"
    elif kind == "transmission_error":
        i = draw(st.sampled_from([0, 1]))
        te = doc["meshes"][i]["transmission_error"]
        j = draw(st.sampled_from(range(len(te))))
        twice["meshes"][i]["transmission_error"].append(copy.deepcopy(te[j]))
        del none["meshes"][i]["transmission_error"][j]
    else:
        return kind, *_refused(kind, twice, draw)
    return kind, twice, none, once


def _refused(kind: str, doc: dict[str, Any], draw: st.DrawFn) -> tuple[dict[str, Any], None, str]:
    shaft = doc["shafts"][0]
    if kind == "bearing_name":
        shaft["bearings"].append(copy.deepcopy(shaft["bearings"][0]))
        return doc, None, "shafts[0].bearings[2]"
    if kind == "disk_node":
        shaft["disks"].append(copy.deepcopy(shaft["disks"][0]))
        return doc, None, "shafts[0].disks[1]"
    if kind == "layer_elements":
        shaft["layers"][0]["elements"] = [0, 1, 0]
        return doc, None, "shafts[0].layers[0]"
    if kind == "inertia":
        big = draw(st.sampled_from([0.05, 0.5, 5.0]))
        disk = {
            "node": 1,
            "mass": "7 kg",
            "inertia": ["0.01 kg*m^2", "0.01 kg*m^2", f"{big} kg*m^2"],
        }
        shaft["disks"][0] = disk
        return doc, None, "shafts[0].disks[0]"
    if kind == "single_double":
        m = doc["meshes"][0]
        m["single_stiffness"], m["double_stiffness"] = m["double_stiffness"], m["single_stiffness"]
        return doc, None, "meshes[0]"
    if kind == "negative_stiffness":
        shaft["bearings"][1]["stiffness"] = [["-5e7 N/m", "0 N/m"], ["0 N/m", "4e7 N/m"]]
        return doc, None, "shafts[0].bearings[1].stiffness"
    if kind == "body_name":
        doc["rigid_bodies"] = [{"name": "rotor", "position": [0, 0, 1], "mass": 1.0,
                                "inertia": [1, 1, 1]}]  # fmt: skip
        return doc, None, "rigid_bodies[0].name"
    if kind == "components":
        shaft["bearings"][1]["components"] = ["ux", "ux"]
        return doc, None, "shafts[0].bearings[1]"
    if kind == "speeds":
        b = shaft["bearings"][1]
        b["speeds"] = "1000 1000 3000 rpm"
        b["stiffness"] = [b["stiffness"]] * 3
        return doc, None, "shafts[0].bearings[1]"
    if kind == "positions":
        shaft["positions"] = "0 300 300 600 mm"
        return doc, None, "shafts[0]"
    if kind == "link":
        doc["rigid_bodies"] = [{"name": "hub", "position": ["0 mm", "0 mm", "600 mm"],
                                "mass": 1.0, "inertia": [0.01, 0.01, 0.02]}]  # fmt: skip
        link = {"name": "weld", "body": "rotor", "node": 2, "other_body": "hub", "other_node": 0}
        doc["rigid_links"] = [link, dict(link, name="weld_again")]
        return doc, None, "rigid_links"
    shaft["disks"][0] = {"node": 1, "mass": "-7 kg", "inertia": [0.1, 0.1, 0.2]}
    return doc, None, "shafts[0].disks[0].mass"


def _parts(doc: dict[str, Any], speed: float) -> dict[str, np.ndarray]:
    from rheolin.io import parse_document

    s = parse_document(copy.deepcopy(doc)).model.assemble(speed).system
    out = {f"{x}{k}": getattr(s, x)[k].toarray() for x in "MDK" for k in getattr(s, x)}
    out.update({f"f{k}": np.asarray(v) for k, v in s.f.items()})
    return out


def check_semantic(case: tuple[str, dict[str, Any], dict[str, Any] | None, Any]) -> str:
    """``"adds"`` or ``"refused"`` when the promise holds; AssertionError otherwise."""
    from rheolin.errors import ModelError
    from rheolin.io import parse_document

    kind, twice, none, original = case
    if none is None:
        try:
            parse_document(copy.deepcopy(twice))
        except ModelError as exc:
            assert str(exc).startswith(original) or original in str(exc), (kind, str(exc))
            return "refused"
        raise AssertionError(f"{kind}: accepted, but the format refuses it ({original})")
    speed = 300.0
    a, b, c = _parts(twice, speed), _parts(original, speed), _parts(none, speed)
    for key in sorted(set(a) | set(b) | set(c)):
        x2, x1, x0 = (p.get(key, 0.0) for p in (a, b, c))
        scale = max(float(np.abs(x2).max(initial=0.0)), float(np.abs(x1).max(initial=0.0)), 1e-300)
        gap = float(np.abs((np.asarray(x2) - x1) - (np.asarray(x1) - x0)).max(initial=0.0))
        assert gap <= 1e-9 * scale, (kind, key, gap, scale)
    return "adds"
