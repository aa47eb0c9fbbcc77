"""The study's results from its chunks: one Dataset over ``(*parameters, speed)``.

Without parameters the Dataset is exactly what :func:`rheolin.results.sweep.sweep_speeds`
returns (``sweep.nc``), plus ``message`` and ``seconds`` per point. A point that raised has
``success = 0``, ``status = -1`` (:data:`STATUS_ERROR`), ``stable = -1`` and NaN amplitudes.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import xarray as xr

from ..results.sweep import STABILITY_FLAGS, speed_coordinates, sweep_attrs
from .spec import StudySpec

__all__ = ["STATUS_ERROR", "assemble", "maps_dataset", "parameter_coords"]

#: ``status`` of a point that raised an error (its ``message`` says which).
STATUS_ERROR = -1

_FLOQUET = ("floquet_pickle", "floquet_offset", "floquet_size")
#: Fill values of points that were not computed.
_FILL = {"success": 0, "status": STATUS_ERROR, "iterations": -1, "stable": -1}


def parameter_coords(spec: StudySpec) -> dict[str, Any]:
    """One coordinate per parameter: its values, with ``units`` and ``field`` attributes."""
    return {
        p.path: (p.path, np.array(p.values), {"units": p.unit or "SI", "field": p.field})
        for p in spec.parameters
    }


def assemble(
    spec: StudySpec,
    chunks: list[xr.Dataset],
    failures: dict[int, str],
    settings: dict[str, Any],
) -> xr.Dataset:
    """Stack the chunks into the study's Dataset; ``settings`` (method, order, max_order) go
    to the attributes."""
    n = spec.n_points
    parts = [c.drop_vars(_FLOQUET, errors="ignore").drop_vars("speed") for c in chunks]
    if parts:
        flat = xr.concat(parts, dim="point", join="outer", coords="different", compat="equals")
        if not np.array_equal(flat["point"].values, np.arange(n)):  # else nothing to move
            flat = flat.sortby("point")
            if np.unique(flat["point"].values).size != flat.sizes["point"]:
                raise ValueError("a point appears in two chunks")
            flat = flat.reindex(point=np.arange(n))
    else:
        flat = xr.Dataset(coords={"point": np.arange(n)})
    lead = (*spec.dims,)
    data: dict[str, Any] = {}
    for name, var in flat.data_vars.items():
        values = var.transpose("point", ...).values
        rest = [d for d in var.dims if d != "point"]
        if name in _FILL:
            values = np.where(np.isnan(values.astype(float)), _FILL[name], values).astype(int)
        elif values.dtype == object:
            values = np.where(
                np.array([isinstance(v, str) for v in values.ravel()]).reshape(values.shape),
                values,
                "",
            ).astype(str)
        values = values.reshape(*spec.shape, *values.shape[1:])
        data[str(name)] = ((*lead, *rest), values, var.attrs)
    for key, fill in _FILL.items():
        if key not in data:
            data[key] = (lead, np.full(spec.shape, fill))
    for key in ("method", "message"):
        if key not in data:
            data[key] = (lead, np.full(spec.shape, "", dtype=object).astype(str))
    message = data["message"][1]
    flat_message = message.reshape(-1)
    done = np.zeros(n, dtype=bool)
    for c in chunks:
        done[c["point"].values.astype(int)] = True
    for i in np.flatnonzero(~done):
        flat_message[i] = failures.get(int(i), "not computed")
    data["message"] = (lead, flat_message.astype(str).reshape(spec.shape))
    data["stable"] = (
        lead,
        data["stable"][1],
        {"flag_values": STABILITY_FLAGS},
    )
    harmonic = flat["harmonic"].values if "harmonic" in flat.coords else np.zeros(0, dtype=int)
    w1 = float(chunks[0].attrs["w1_per_speed"]) if chunks else float("nan")
    coords = {**parameter_coords(spec), **speed_coordinates(spec.speeds, harmonic, w1)}
    for name in ("node", "body", "bearing", "mesh"):
        if name in flat.coords:
            coords[name] = (flat[name].dims[0], flat[name].values)
    ds = xr.Dataset(data, coords=coords)
    orders = json.loads(chunks[0].attrs.get("marker_orders_json", "{}")) if chunks else {}
    ds.attrs.update(sweep_attrs(settings, orders))
    ds.attrs.update(
        model_sha256=spec.model_sha256,
        model_file=spec.source,
        study_key=spec.key,
        parameters_json=json.dumps(
            [{"path": p.path, "field": p.field, "unit": p.unit} for p in spec.parameters]
        ),
    )
    ds["status"].attrs["flag_values"] = "see rheolin.STATUS; -1: the point raised an error"
    return ds


def maps_dataset(spec: StudySpec, maps: dict[int, Any]) -> xr.Dataset | None:
    """The stability maps of every combination as one Dataset: per-speed variables over
    ``(*parameters, speed)`` (NaN/False where a combination has no map), the unstable ranges
    along ``range`` with the parameter values of each (``range_<path>``)."""
    if not maps:
        return None
    if not spec.parameters:
        return maps[0].to_dataset() if 0 in maps else None
    per_speed, ranges = [], []
    for combo in range(spec.n_combos):
        smap = maps.get(combo)
        if smap is None:
            continue
        ds = smap.to_dataset()
        speed_vars = [v for v in ds.data_vars if "speed" in ds[v].dims]
        s = ds[speed_vars].reindex(speed=spec.speeds)
        per_speed.append(s.expand_dims(combo=[combo]))
        r = ds[[v for v in ds.data_vars if "range" in ds[v].dims]]
        if r.sizes.get("range", 0):
            extra = {"range_combo": ("range", np.full(r.sizes["range"], combo))}
            for p, i in spec.assignments(combo):
                extra[f"range_{p.path}"] = ("range", np.full(r.sizes["range"], p.values[i]))
            ranges.append(r.assign(extra))
    speed_part = xr.concat(per_speed, dim="combo").reindex(combo=np.arange(spec.n_combos))
    out: dict[str, Any] = {}
    for name, var in speed_part.data_vars.items():
        values = var.transpose("combo", "speed").values.reshape(spec.shape)
        out[name] = (spec.dims, values, var.attrs)
    coords = {**parameter_coords(spec), "speed": ("speed", spec.speeds, {"units": "rad/s"})}
    result = xr.Dataset(out, coords=coords)
    if ranges:
        result = result.merge(xr.concat(ranges, dim="range"))
    result.attrs["title"] = "Floquet stability maps"
    return result
