"""The result files of a study, written atomically into its output directory.

* ``sweep.nc``: :attr:`StudyResult.dataset` (``stable`` flagged 1/0/-1/-2:
  :data:`~rheolin.results.sweep.STABILITY_FLAGS`; ``max_floquet_real`` with its
  ``max_floquet_real_uncertainty``) plus ``map_max_real`` (the map's largest Floquet real part
  per point);
* ``stability_map.nc`` (with the map): :meth:`StudyResult.stability_dataset`;
* ``sweep.json``: per point ``success``, ``status``, ``iterations``, ``stable`` (true, false,
  or null when not checked or undecided) and ``stability`` (``"stable"``, ``"unstable"``,
  ``"undecided"``, ``"not checked"``), nested as ``(*parameters, speed)``; every unstable
  range (bounds and their uncertainties in rpm, open ends, largest real part, ``mechanism``
  category, one-line ``label`` and the mechanism's ``detail``) with its parameter values,
  the failed points with their messages, the resonance peaks of a speed sweep with their
  half-power amplification factors (API 684), warnings;
* plots: ``sweep.png`` and ``stability_map.png`` without parameters, one
  ``vary_<parameter>.png`` per parameter otherwise.

Files of an earlier run of the same study that this run does not write are removed, so the
directory never mixes runs.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from ..io.atomic import atomic_write
from ..results.dataset import write_dataset
from ..results.schema import SCHEMA_VERSION
from ..results.sweep import STABILITY_STATES
from ..results.units import significant
from .store import CheckpointStore

__all__ = ["plot_name", "resonances", "sweep_table", "write_results"]

RPM = 30 / np.pi


def plot_name(path: str) -> str:
    """File name of a parameter's plot: ``vary_bearings.input_A.stiffness.png``."""
    return "vary_" + re.sub(r"[^A-Za-z0-9_.-]+", "_", path) + ".png"


def write_results(
    result: Any, store: CheckpointStore, *, plots: bool = True, quantity: str = "response"
) -> list[Path]:
    """Write the result files of ``result`` (a :class:`~rheolin.study.StudyResult`) into the
    store's directory; returns their paths."""
    out = store.directory
    spec = result.spec
    ds = result.dataset.copy()
    sds = result.stability_dataset()
    if sds is not None:
        ds["map_max_real"] = (
            spec.dims,
            np.asarray(sds["max_real"].reindex(speed=spec.speeds).values, dtype=float),
            {"units": "1/s"},
        )
    ds.attrs["stability_map"] = "computed" if sds is not None else "not computed"
    written = [write_dataset(ds, out / "sweep.nc")]
    if sds is not None:
        written.append(write_dataset(sds, out / "stability_map.nc"))
    with atomic_write(out / "sweep.json") as tmp:
        tmp.write_text(json.dumps(sweep_table(result), indent=2) + "\n")
    written.append(out / "sweep.json")
    if plots:
        written += _plots(result, ds, out, quantity)
    store.remove_outputs(p.name for p in written)
    return written


def sweep_table(result: Any) -> dict[str, Any]:
    """The content of ``sweep.json``."""
    spec, ds = result.spec, result.dataset
    ranges = []
    for combo, smap in sorted(result.maps.items()):
        values = {p.path: p.values[i] for p, i in spec.assignments(combo)}
        for r in smap.ranges:
            ranges.append(
                {
                    "parameters": values,
                    "lower_rpm": significant(r.lower * RPM),
                    "upper_rpm": significant(r.upper * RPM),
                    "lower_uncertainty_rpm": _finite(r.lower_uncertainty * RPM),
                    "upper_uncertainty_rpm": _finite(r.upper_uncertainty * RPM),
                    "open_below": r.lower_open,
                    "open_above": r.upper_open,
                    "max_real_per_s": r.max_real,
                    "mechanism": r.mechanism,
                    "label": r.label,
                    "detail": None if r.detail is None else r.detail.to_dict(),
                }
            )
    failed = []
    for point, message in sorted(result.failures.items()):
        combo = spec.combo_of(point)
        failed.append(
            {
                "parameters": {p.path: p.values[i] for p, i in spec.assignments(combo)},
                "speed_rpm": significant(float(spec.speeds[spec.speed_of(point)]) * RPM),
                "message": message,
            }
        )
    stable = ds["stable"].values
    return {
        "schema": "rheolin.sweep",
        "schema_version": SCHEMA_VERSION,
        "model_file": spec.source,
        "model_sha256": spec.model_sha256,
        "study_key": spec.key,
        "parameters": [
            {"path": p.path, "field": p.field, "unit": p.unit or "SI", "values": list(p.values)}
            for p in spec.parameters
        ],
        "speeds_rpm": [significant(x) for x in spec.speeds * RPM],
        "success": ds["success"].values.astype(bool).tolist(),
        "status": ds["status"].values.tolist(),
        "iterations": ds["iterations"].values.tolist(),
        "stable": _nested(stable, lambda v: None if v < 0 else bool(v)),
        "stability": _nested(stable, lambda v: STABILITY_STATES[int(v)]),
        "unstable_ranges_rpm": [(r["lower_rpm"], r["upper_rpm"]) for r in ranges],
        "unstable_ranges": ranges,
        "failed": failed,
        "resonances": resonances(result),
        "points": {"total": spec.n_points, "resumed": result.resumed, "computed": result.computed},
        "warnings": result.warnings,
    }


def resonances(result: Any) -> list[dict[str, Any]]:
    """The resonance peaks of a speed sweep (no parameters), per body at its most responsive
    node: the oscillating radial response (sum over harmonics, as ``sweep.png``) against speed,
    with the half-power amplification factor (:mod:`rheolin.results.api684`). Empty for a
    parameter study, fewer than five speeds, or no response."""
    from ..results.api684 import amplification_factors

    spec, ds = result.spec, result.dataset
    if spec.parameters or "response" not in ds or spec.speeds.size < 5:
        return []
    resp = ds["response"].where(ds["harmonic"] > 0, 0.0).sum("harmonic")  # (point, node)
    speeds = np.asarray(spec.speeds, dtype=float)
    order = np.argsort(speeds)
    out = []
    for body in dict.fromkeys(np.asarray(ds["body"].values).tolist()):
        per = resp.where(ds["body"] == body, drop=True)
        values = np.asarray(per.values, dtype=float)[order]
        ok = np.all(np.isfinite(values), axis=1)
        if ok.sum() < 5 or not np.any(values[ok] > 0):
            continue
        j = int(np.nanargmax(values[ok].max(axis=0)))
        node = str(per["node"].values[j])
        for p in amplification_factors(speeds[order][ok], values[ok][:, j]):
            out.append(
                {
                    "body": str(body),
                    "node": node,
                    "speed_rpm": significant(p.speed * RPM),
                    "amplitude_m": p.amplitude,
                    "amplification_factor": p.amplification_factor,
                    "half_power_rpm": None
                    if p.lower is None or p.upper is None
                    else [significant(p.lower * RPM), significant(p.upper * RPM)],
                    "samples_in_band": p.samples,
                    "resolved": p.resolved,
                }
            )
    return out


def _nested(values: np.ndarray, convert: Any) -> Any:
    """``values.tolist()`` with each entry converted."""
    if values.ndim == 0:
        return convert(values.item())
    return [_nested(v, convert) for v in values]


def _plots(result: Any, ds: xr.Dataset, out: Path, quantity: str) -> list[Path]:
    from ..plots import sweep_plot
    from ..plots.stability import plot_stability
    from ..plots.study import QUANTITIES, parameter_plot

    spec = result.spec
    if not spec.parameters:
        if "response" not in ds:  # every point failed: nothing to draw
            return []
        smap = result.maps.get(0)
        ranges = [] if smap is None else [(r.lower * RPM, r.upper * RPM) for r in smap.ranges]
        paths = [sweep_plot(ds, out / "sweep.png", ranges)]
        if smap is not None:
            paths.append(plot_stability(smap, out / "stability_map.png"))
        return paths
    if QUANTITIES[quantity][0] and quantity not in ds:  # every point failed: nothing to draw
        return []
    return [
        parameter_plot(result, p.path, out / plot_name(p.path), quantity) for p in spec.parameters
    ]


def _finite(x: float) -> float | None:
    """JSON has no NaN: None instead (an open end's uncertainty)."""
    return float(x) if np.isfinite(x) else None
