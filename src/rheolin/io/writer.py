"""Write a :class:`~rheolin.mechanics.Model` as a model file (``Model.to_toml``).

The model file is the model's ``add_*`` calls one to one (``docs/model-format.md``), so the
writer replays :attr:`Model.calls`: every call becomes its table with the arguments that were
given, in SI units and with full float precision (``repr``), so loading the file gives the
same matrices bit for bit. Condensed bodies given as in-memory matrices and gear meshes given
by a Fourier series of mesh stiffness have no file form and are refused.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w

from ..errors import ModelError
from ..mechanics.sections import Section
from .atomic import atomic_write
from .planetary import planetary_table

__all__ = ["model_to_toml"]


def _plain(value: Any) -> Any:
    """TOML-ready values: arrays to lists, numpy scalars to Python, Fractions to text."""
    if isinstance(value, Fraction):
        return str(value)
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Section):
        return {k: float(getattr(value, k)) for k in
                ("area", "Iy", "Iz", "torsion_constant", "kappa_y", "kappa_z")}  # fmt: skip
    return value


def _args(call: dict[str, Any], drop: tuple[str, ...] = ()) -> dict[str, Any]:
    return {k: _plain(v) for k, v in call.items() if v is not None and k not in drop}


def _material(model: Any, method: str, t: dict[str, Any]) -> dict[str, Any]:
    """Write the material constants a call took from the API's defaults: the file format
    assumes no material (docs/model-format.md)."""
    import inspect

    params = inspect.signature(getattr(model, method)).parameters
    keys = ("elastic_modulus", "density") if method != "add_disk" else ("density",)
    if method == "add_disk" and t.get("outer_diameter") is None:
        return t
    for key in keys:
        default = params[key].default if key in params else None
        if key not in t and isinstance(default, (int, float)):
            t[key] = float(default)
    if method != "add_disk" and "shear_modulus" not in t and "poisson_ratio" not in t:
        default = params["poisson_ratio"].default if "poisson_ratio" in params else None
        t["poisson_ratio"] = 0.3 if default is None else float(default)
    return t


def _bearing(a: dict[str, Any]) -> dict[str, Any]:
    comps = a.get("components", ("ux", "uy"))
    out = _args(a, ("body",))
    out["components"] = "all" if comps is None else list(comps)
    return out


def model_to_toml(model: Any, path: str | Path | None = None) -> str:
    """The model file text of ``model``; also written atomically to ``path`` if given.

    Examples
    --------
    >>> from rheolin.mechanics import Model
    >>> m = Model()
    >>> m.add_shaft("s", [0.0, 0.5], outer_diameter=0.05, shear_modulus=80e9,
    ...            material="steel")
    >>> m.add_bearing("b", "s", 0, 1e7)
    >>> text = model_to_toml(m)
    >>> "shear_modulus = 80000000000.0" in text, "[[shafts.bearings]]" in text
    (True, True)
    """
    doc: dict[str, Any] = {"model": {}}
    if model.input_body is not None:
        doc["model"]["input_body"] = model.input_body
    if model.unbalance_reference is not None:
        doc["model"]["unbalance_reference"] = list(model.unbalance_reference)
    tables: dict[str, dict[str, Any]] = {}
    lists: dict[str, list[dict[str, Any]]] = {
        "shafts": [], "rigid_bodies": [], "condensed_bodies": [], "meshes": [], "forces": [],
        "torques": [], "rigid_links": [], "planetary": [],
    }  # fmt: skip
    for method, call in model.calls:
        if method == "add_shaft":
            t = _material(model, method, _args(call))
            tables[call["name"]] = t
            lists["shafts"].append(t)
        elif method == "add_shaft_layer":
            t = _material(model, method, _args(call, ("shaft",)))
            tables[call["shaft"]].setdefault("layers", []).append(t)
        elif method == "add_rigid_body":
            t = _args(call)
            tables[call["name"]] = t
            lists["rigid_bodies"].append(t)
        elif method == "add_condensed_body":
            if call.get("path") is None:
                raise ModelError(
                    f"condensed body {call['name']!r}: given as matrices, it has no file form; "
                    "save it to .npz and add it with `path=`"
                )
            t = _args(call, ("body",))
            tables[call["name"]] = t
            lists["condensed_bodies"].append(t)
        elif method == "add_disk":
            t = _material(model, method, _args(call, ("body",)))
            tables[call["body"]].setdefault("disks", []).append(t)
        elif method == "add_bearing":
            tables[call["body"]].setdefault("bearings", []).append(_bearing(call))
        elif method == "add_gear_mesh":
            t = _args(call, ("transmission_error", "center_direction"))
            if isinstance(call.get("stiffness"), dict) or call.get("center_direction") is not None:
                raise ModelError(
                    f"gear mesh {call['name']!r}: a Fourier series of mesh stiffness or a "
                    "`center_direction` has no file form"
                )
            te = call.get("transmission_error") or {}
            t["transmission_error"] = [
                {"harmonic": 0, "amplitude": abs(float(np.real(e))),
                 "phase": 0.0 if np.real(e) >= 0 else float(np.pi)} if j == 0
                else {"harmonic": int(j), "amplitude": 2 * abs(e), "phase": float(np.angle(e))}
                for j, e in te.items()
            ]  # fmt: skip
            lists["meshes"].append(t)
        elif method == "add_force":
            lists["forces"].append(_args(call))
        elif method == "add_rolling_bearing":
            t = _args(call, ("body",))
            tables[call["body"]].setdefault("rolling_bearings", []).append(t)
        elif method == "add_torque":
            lists["torques"].append(_args(call))
        elif method == "add_rigid_link":
            lists["rigid_links"].append(_args(call))
        elif method == "add_planetary":
            lists["planetary"].append(planetary_table(call))
        elif method == "set_gravity":
            doc["model"]["gravity"] = _plain(np.asarray(call.get("gravity", (0.0, -9.81, 0.0))))
    for key, items in lists.items():
        if items:
            doc[key] = items
    text = tomli_w.dumps(doc)
    if path is not None:
        with atomic_write(path) as tmp:
            tmp.write_text(text)
    return text
