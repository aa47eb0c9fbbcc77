"""Results over speed: one amplitude spectrum per speed (radial, single-sided ``2|x_n|``).

The harmonic set is fixed in orders of the input speed (closure with ``max_order``), so every
speed shares the same ``harmonic`` indices; ``frequency`` is a ``(speed, harmonic)`` coordinate.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import xarray as xr

from .. import __version__
from ..mechanics.joints import COMPONENTS
from ..mechanics.model import Model
from .compute import OperatingPoint, solve_point
from .dataset import frequency_markers
from .outputs import bearing_force_array, global_displacements, transmission_error_array

__all__ = [
    "STABILITY_FLAGS",
    "STABILITY_STATES",
    "floquet_uncertainty",
    "point_amplitudes",
    "speed_coordinates",
    "stability_flag",
    "sweep_attrs",
    "sweep_dataset",
    "sweep_speeds",
]


def point_amplitudes(point: OperatingPoint) -> dict[str, xr.DataArray]:
    """Single-sided amplitudes of a solved point, from its arrays (a sweep keeps only
    these, so the point's full Dataset is not built): radial ``response(harmonic, node)``,
    ``bearing_force(bearing, harmonic)``, ``dte(mesh, harmonic)``. Coordinates ``harmonic``,
    ``node`` (with ``body``), ``bearing``, ``mesh``."""
    a, sol = point.assembled, point.solution
    keep = sol.harmonics >= 0
    harmonics = sol.harmonics[keep]
    two = np.where(harmonics > 0, 2.0, 1.0)
    nodes = list(a.node_index)
    ix, iy = COMPONENTS.index("ux"), COMPONENTS.index("uy")
    idx = np.array([6 * a.node_index[k] for k in nodes], dtype=np.int64)
    q = global_displacements(sol, a)
    coords: dict[str, Any] = {
        "harmonic": ("harmonic", harmonics),
        "node": ("node", [f"{b}:{i}" for b, i in nodes]),
        "body": ("node", [b for b, _ in nodes]),
    }
    radial = np.hypot(np.abs(q[:, idx + ix]), np.abs(q[:, idx + iy])) * two[:, None]
    out = {"response": xr.DataArray(radial, dims=("harmonic", "node"), coords=coords)}
    names = list(a.joints)
    if names:
        F = np.array([bearing_force_array(sol, a, j)[1] for j in names])  # (bearing, h, 6)
        Fr = np.hypot(np.abs(F[..., 0]), np.abs(F[..., 1])) * two[None, :]
        out["bearing_force"] = xr.DataArray(
            Fr,
            dims=("bearing", "harmonic"),
            coords={"bearing": ("bearing", names), "harmonic": ("harmonic", harmonics)},
        )
    meshes = list(a.meshes)
    if meshes:
        E = np.array([transmission_error_array(sol, a, m)[1] for m in meshes])
        out["dte"] = xr.DataArray(
            np.abs(E) * two[None, :],
            dims=("mesh", "harmonic"),
            coords={"mesh": ("mesh", meshes), "harmonic": ("harmonic", harmonics)},
        )
    return out


def sweep_speeds(
    model: Model,
    speeds: Sequence[float],
    *,
    progress: Callable[[int, OperatingPoint], None] | None = None,
    **options: Any,
) -> xr.Dataset:
    """Solve at every input speed [rad/s] and collect amplitude spectra (see :func:`solve_point`).

    The model is assembled once (:class:`~rheolin.mechanics.template.SpeedTemplate`), and each
    speed starts from the converged solution of the previous one when both share the harmonic
    set (a warm start: fewer iterations, same tolerance), and its Floquet searches from the
    previous speed's eigenvectors (:class:`~rheolin.floquet.Continuation`).

    >>> from rheolin.io import load_model
    >>> from rheolin.data import example_path
    >>> ds = sweep_speeds(load_model(example_path("rotor")), [100.0, 200.0], stability=False)
    >>> ds["response"].dims, ds["success"].values.tolist()
    (('speed', 'harmonic', 'node'), [1, 1])
    """
    from ..floquet import Continuation

    points = []
    template = model.speed_template()
    previous = None
    options.setdefault("continuation", Continuation())
    for i, w in enumerate(speeds):
        p = solve_point(model, float(w), template=template, x0=previous, **options)
        points.append(_reduce(p))
        ok = p.solution.success and np.all(np.isfinite(p.solution.q))
        previous = p.solution if ok else None
        if progress is not None:
            progress(i, p)
    return sweep_dataset(points, options)


def _reduce(p: OperatingPoint) -> dict[str, Any]:
    amps = point_amplitudes(p)
    s = p.solution
    return dict(
        speed=p.assembled.speed,
        amps=amps,
        coords=xr.Dataset(amps).coords,
        success=int(s.success),
        status=int(s.status),
        iterations=int(s.iterations),
        residual=float(s.residual),
        stable=stability_flag(s.stable, s.floquet),
        max_floquet_real=float("nan") if s.max_floquet_real is None else s.max_floquet_real,
        max_floquet_real_uncertainty=floquet_uncertainty(s.floquet),
        method=s.method,
        markers=frequency_markers(p.assembled),
        base_ratio=float(p.assembled.base_ratio),
    )


def sweep_dataset(points: list[dict[str, Any]], options: dict[str, Any]) -> xr.Dataset:
    """Stack reduced operating points into one Dataset over ``speed``."""
    first = points[0]
    speeds = np.array([p["speed"] for p in points])
    data: dict[str, Any] = {}
    for key, units in (("response", "m"), ("bearing_force", "N"), ("dte", "m")):
        if key in first["amps"]:
            dims = ("speed", *first["amps"][key].dims)
            values = np.stack([p["amps"][key].values for p in points])
            data[key] = (dims, values, {"units": units, "long_name": f"{key} amplitude"})
    scalars = ("success", "status", "iterations", "residual", "stable", "max_floquet_real")
    for key in (*scalars, "max_floquet_real_uncertainty"):
        data[key] = ("speed", np.array([p[key] for p in points]))
    data["stable"] = data["stable"] + ({"flag_values": STABILITY_FLAGS},)
    data["max_floquet_real_uncertainty"] += ({"units": "1/s"},)
    data["method"] = ("speed", np.array([p["method"] for p in points]))
    harmonic = first["coords"]["harmonic"].values
    coords = speed_coordinates(speeds, harmonic, first["base_ratio"])
    for name in ("node", "body", "bearing", "mesh"):
        if name in first["coords"]:
            c = first["coords"][name]
            coords[name] = (c.dims[0], c.values)
    ds = xr.Dataset(data, coords=coords)
    orders = {k: v / (first["speed"] / (2 * math.pi)) for k, v in first["markers"].items()}
    ds.attrs.update(sweep_attrs(options, orders))
    return ds


def speed_coordinates(
    speeds: np.ndarray, harmonic: np.ndarray, w1_per_speed: float
) -> dict[str, Any]:
    """``speed`` [rad/s], ``speed_rpm``, ``harmonic``, its ``order`` and the
    ``frequency(speed, harmonic)`` [Hz] of a result over speed."""
    return {
        "speed": ("speed", speeds, {"units": "rad/s"}),
        "speed_rpm": ("speed", speeds * 30 / math.pi, {"units": "rpm"}),
        "harmonic": ("harmonic", harmonic),
        "order": ("harmonic", harmonic * w1_per_speed, {"units": "1"}),
        "frequency": (
            ("speed", "harmonic"),
            np.outer(speeds, harmonic) * w1_per_speed / (2 * math.pi),
            {"units": "Hz"},
        ),
    }


def sweep_attrs(options: dict[str, Any], marker_orders: dict[str, float]) -> dict[str, Any]:
    """Attributes of a result over speed: settings, plot markers (shaft and mesh orders)."""
    return dict(
        rheolin_version=__version__,
        method=str(options.get("method", "auto")),
        closure_order=int(options.get("order", 2)),
        max_order=float(options.get("max_order") or 0.0),
        marker_orders_json=json.dumps(marker_orders),
        convention="single-sided amplitudes 2|x_n| (|x_0| for the mean); radial = hypot(x, y)",
    )


#: The values of the ``stable`` flag of sweep.nc and of a study's points.
STABILITY_FLAGS = "1 stable, 0 unstable, -1 not checked, -2 undecided"

#: The state each flag value stands for (sweep.json's ``stability``).
STABILITY_STATES = {1: "stable", 0: "unstable", -1: "not checked", -2: "undecided"}


def stability_flag(stable: bool | None, floquet: Any) -> int:
    """The ``stable`` flag of a point: -1 not checked, -2 when its Floquet verdict is not
    decided (whichever side it leans to: never reported stable), else 1 or 0.

    >>> from types import SimpleNamespace
    >>> stability_flag(True, SimpleNamespace(decided=False)), stability_flag(None, None)
    (-2, -1)
    """
    if stable is None:
        return -1
    if floquet is not None and not floquet.decided:
        return -2
    return int(stable)


def floquet_uncertainty(floquet: Any) -> float:
    """The stated uncertainty of a point's largest Floquet real part [1/s] (NaN: none)."""
    u = getattr(floquet, "max_real_uncertainty", None)
    return float("nan") if u is None else float(u)
