"""The readable summary of one operating point: a plain dict (``summary.json``) and its text.

Amplitudes are single-sided peak values ``2 |x_n|`` (``|x_0|`` for the mean).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from ..io.atomic import atomic_write
from .dataset import complex_values
from .schema import SCHEMA_VERSION

__all__ = ["summarize", "write_summary"]


def _amp(z: xr.DataArray) -> xr.DataArray:
    scale = xr.where(z["harmonic"] > 0, 2.0, 1.0)
    return np.abs(z) * scale


def _top(amp: xr.DataArray, k: int = 3) -> list[dict[str, Any]]:
    """The ``k`` largest harmonics of a 1-D amplitude over ``harmonic``."""
    order = np.argsort(-amp.values)[:k]
    return [
        {
            "harmonic": int(amp["harmonic"].values[i]),
            "frequency_hz": float(amp["frequency"].values[i]),
            "order": float(amp["order"].values[i]),
            "amplitude": float(amp.values[i]),
        }
        for i in order
        if amp.values[i] > 0
    ]


def summarize(ds: xr.Dataset) -> dict[str, Any]:
    """Summary dict: solver diagnostics, largest responses per body, bearing forces, mesh DTE.

    Only the oscillating part (``n > 0``) enters the "largest response" tables; the static
    deflection (``n = 0``) is reported separately per body.
    """
    keys: tuple[str, ...] = (
        "speed",
        "speed_rpm",
        "base_frequency",
        "method",
        "requested_method",
        "success",
    )
    keys += ("status", "message", "iterations", "residual", "residual_kind", "relative_residual")
    keys += ("rtol", "stability", "max_floquet_real", "max_floquet_real_uncertainty")
    keys += ("stability_decided", "floquet_method", "floquet_lattice_order", "floquet_lattice_size")
    keys += ("leading_exponent_real", "leading_exponent_frequency_hz", "floquet_seconds")
    keys += ("stability_mechanism", "stability_open")
    keys += ("harmonic_count", "closure_order", "max_order", "n_dof", "model_sha256")
    out: dict[str, Any] = {"schema": "rheolin.summary", "schema_version": SCHEMA_VERSION}
    out.update({k: _plain(ds.attrs.get(k)) for k in keys})
    for flag in ("success", "stability_decided"):  # JSON booleans (docs/results-schema.md)
        if out.get(flag) is not None:
            out[flag] = bool(out[flag])
    q = complex_values(ds["displacement"])
    radial = np.hypot(np.abs(q.sel(component="ux")), np.abs(q.sel(component="uy")))
    radial = radial * xr.where(q["harmonic"] > 0, 2.0, 1.0)
    dyn = radial.where(radial["harmonic"] > 0, 0.0)
    bodies: dict[str, Any] = {}
    for body in dict.fromkeys(ds["body"].values.tolist()):
        sub = dyn.where(ds["body"] == body, drop=True)
        total = sub.sum("harmonic")  # upper bound of the radial dynamic amplitude
        node = str(total.idxmax("node").values)
        bodies[body] = {
            "node": node,
            "radial_amplitude_bound_m": float(total.max()),
            "static_radial_m": float(radial.sel(harmonic=0).where(ds["body"] == body).max())
            if 0 in ds["harmonic"].values
            else 0.0,
            "largest_harmonics": _top(sub.sel(node=node), 3),
        }
    out["bodies"] = bodies
    if "bearing_force" in ds:
        F = complex_values(ds["bearing_force"])
        Fr = np.hypot(np.abs(F.sel(force_component="Fx")), np.abs(F.sel(force_component="Fy")))
        Fr = Fr * xr.where(F["harmonic"] > 0, 2.0, 1.0)
        out["bearings"] = {
            str(b): {
                "static_radial_N": float(Fr.sel(bearing=b, harmonic=0))
                if 0 in ds["harmonic"].values
                else 0.0,
                "dynamic_radial_sum_N": float(Fr.sel(bearing=b).where(Fr["harmonic"] > 0, 0).sum()),
                "largest_harmonics": _top(Fr.sel(bearing=b).where(Fr["harmonic"] > 0, 0.0), 3),
            }
            for b in ds["bearing"].values
        }
    if "dte" in ds:
        E = _amp(complex_values(ds["dte"]))
        out["meshes"] = {
            str(m): {
                "mean_m": float(E.sel(mesh=m, harmonic=0)) if 0 in ds["harmonic"].values else 0.0,
                "largest_harmonics": _top(E.sel(mesh=m).where(E["harmonic"] > 0, 0.0), 3),
            }
            for m in ds["mesh"].values
        }
    return out


def _plain(v: Any) -> Any:
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def write_summary(summary: dict[str, Any], path: str | Path) -> Path:
    """Write ``summary.json`` atomically."""
    with atomic_write(path) as tmp:
        tmp.write_text(json.dumps(summary, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    return Path(path)
