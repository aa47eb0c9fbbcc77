"""Labelled results (``xarray.Dataset``) of one operating point, and their NetCDF file.

Complex two-sided coefficients are stored with a trailing ``part`` dimension
(``part = ["real", "imag"]``), which every NetCDF reader understands;
:func:`complex_values` turns such a variable back into the complex ``x_n``, and
:func:`complex_amplitude` into the single-sided complex amplitude ``A_n`` (``2 x_n`` for
``n > 0``, ``x_0`` for the mean), with ``x(t) = Re sum_{n >= 0} A_n exp(i n w1 t)``. Only the
harmonics ``n >= 0`` are stored (``x_{-n} = conj(x_n)``). Units: :mod:`rheolin.results.units`.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from .. import __version__
from ..io.atomic import atomic_write
from ..mechanics.assembly import Assembled
from ..mechanics.joints import COMPONENTS
from ..solvers.solution import Solution
from .compute import OperatingPoint
from .outputs import bearing_force_array, global_displacements, transmission_error_array
from .units import significant, with_units

__all__ = [
    "complex_amplitude",
    "complex_values",
    "floquet_attrs",
    "frequency_markers",
    "leading_tolerance",
    "netcdf_engine",
    "orbit_frequencies",
    "point_dataset",
    "stability_text",
    "write_dataset",
]

_UNITS = {"ux": "m", "uy": "m", "uz": "m", "phix": "rad", "phiy": "rad", "phiz": "rad"}
_FORCE_UNITS = {"Fx": "N", "Fy": "N", "Fz": "N", "Mx": "N m", "My": "N m", "Mz": "N m"}


def floquet_attrs(sol: Solution) -> dict[str, Any]:
    """The stability check's details as NetCDF attributes (empty when not checked)."""
    res = sol.floquet
    if res is None:
        return {}
    lead = res.leading
    out: dict[str, Any] = {
        "stability_decided": int(res.decided),
        "floquet_method": res.method,
        "leading_exponent_real": float(lead.real),
        "leading_exponent_frequency_hz": float(abs(lead.imag) / (2 * math.pi)),
        "max_floquet_real_uncertainty": float(res.max_real_uncertainty),
        "floquet_seconds": float(res.info.get("seconds", float("nan"))),
    }
    if res.lattice is not None:
        out["floquet_lattice_order"] = int(res.lattice.order)
        out["floquet_lattice_size"] = len(res.lattice)
    if not res.decided:  # what keeps it open and what to change
        out["stability_open"] = res.open_reason()
    if "stability_mechanism" in sol.info:
        out["stability_mechanism"] = str(sol.info["stability_mechanism"])
    return out


def stability_text(
    stable: bool | None,
    decided: bool | None = None,
    max_real: float | None = None,
    tol: float | None = None,
) -> str:
    """``"stable"``, ``"unstable"``, ``"undecided"`` or ``"not checked"``.

    A "stable" verdict is reported ``"undecided"`` when the truncation could still flip it
    (``decided`` False), or when the largest Floquet real part is positive and no tolerance
    ``tol`` [1/s] of that exponent is given, or it lies above it. A decided stable verdict
    whose largest real part is zero within ``tol`` (an undamped motion; round-off puts it
    on either side of the axis) is ``"stable"``: marginal, as ``FloquetResult.marginal``
    says, and the console's stability line says so.

    >>> stability_text(True), stability_text(True, max_real=1e-3), stability_text(None)
    ('stable', 'undecided', 'not checked')
    >>> stability_text(True, True, 5.8e-16, tol=1e-9), stability_text(True, True, 2e-9, 1e-9)
    ('stable', 'undecided')
    """
    if stable is None:
        return "not checked"
    if not stable:
        return "unstable"
    if decided is False:
        return "undecided"
    if max_real is not None and max_real > 0 and (tol is None or not max_real <= tol):
        return "undecided"
    return "stable"


def leading_tolerance(res: Any) -> float:
    """The tolerance [1/s] of the exponent with the largest real part (``res.tol`` when the
    per-exponent tolerances were not kept)."""
    lam, tol = np.asarray(res.exponents), np.asarray(res.tolerances)
    if lam.size and tol.size == lam.size:
        return float(tol[int(np.argmax(lam.real))])
    return float(res.tol)


def _parts(z: np.ndarray) -> np.ndarray:
    return np.stack([z.real, z.imag], axis=-1)


def complex_values(da: xr.DataArray) -> xr.DataArray:
    """Recombine a variable with a ``part`` dimension into complex values.

    >>> da = xr.DataArray([[1.0, 2.0]], dims=("n", "part"), coords={"part": ["real", "imag"]})
    >>> complex_values(da).values
    array([1.+2.j])
    """
    return da.sel(part="real") + 1j * da.sel(part="imag")


def complex_amplitude(data: xr.Dataset | xr.DataArray) -> Any:
    """Single-sided complex amplitudes of a results variable (or of every variable of a
    Dataset that has a ``part`` axis): ``2 x_n`` for the harmonics ``n > 0``, ``x_0`` for
    the mean, so that ``x(t) = Re sum_{n >= 0} A_n exp(i n w1 t)``; a variable without a
    ``harmonic`` axis (an FRF's receptance: the response to ``F cos(w t)`` is
    ``Re(q e^{i w t})``) is its complex value. Units and attributes are kept.

    >>> da = xr.DataArray([[0.5, 0.0], [1.0, 2.0]], dims=("harmonic", "part"),
    ...                   coords={"harmonic": [0, 3], "part": ["real", "imag"]},
    ...                   attrs={"units": "m"})
    >>> a = complex_amplitude(da)
    >>> a.values.tolist(), a.attrs["units"]
    ([(0.5+0j), (2+4j)], 'm')
    """
    if isinstance(data, xr.Dataset):
        parts = [n for n in data.data_vars if "part" in data[n].dims]
        return xr.Dataset({str(n): complex_amplitude(data[n]) for n in parts}, attrs=data.attrs)
    z = complex_values(data)
    if "harmonic" in z.dims:
        z = z * xr.where(z["harmonic"] > 0, 2.0, 1.0)
    z.attrs = dict(data.attrs)
    return z


def point_dataset(
    point: OperatingPoint, *, model_sha256: str = "", model_name: str = ""
) -> xr.Dataset:
    """Dataset of node displacements, bearing forces and mesh DTE over the harmonics ``n >= 0``.

    Coordinates: ``harmonic`` (index ``n``), ``frequency`` [Hz] and ``order`` (relative to
    the input speed) on ``harmonic``; ``node`` (``"body:i"``) with ``body``, ``node_index``
    and ``position``; ``component``; ``bearing``; ``mesh``; ``part``.
    """
    a, sol = point.assembled, point.solution
    keep = sol.harmonics >= 0
    harmonics = sol.harmonics[keep]
    freq = harmonics * a.omega / (2 * math.pi)
    order = harmonics * float(a.base_ratio)
    nodes = list(a.node_index)
    idx = np.array([6 * a.node_index[k] + np.arange(6) for k in nodes])  # (node, 6)
    q = global_displacements(sol, a)[:, idx]  # (harmonic, node, component), global axes
    coords: dict[str, Any] = {
        "harmonic": ("harmonic", harmonics),
        "frequency": ("harmonic", freq, {"units": "Hz"}),
        "order": ("harmonic", order, {"units": "1", "long_name": "order of the input speed"}),
        "node": ("node", [f"{b}:{i}" for b, i in nodes]),
        "body": ("node", [b for b, _ in nodes]),
        "node_index": ("node", np.array([i for _, i in nodes])),
        "component": ("component", list(COMPONENTS)),
        "component_units": ("component", [_UNITS[c] for c in COMPONENTS]),
        "force_component": ("force_component", list(_FORCE_UNITS)),
        "force_component_units": ("force_component", list(_FORCE_UNITS.values())),
        "part": ("part", ["real", "imag"]),
        "xyz": ("xyz", ["x", "y", "z"]),
    }
    data: dict[str, Any] = {
        "displacement": (
            ("harmonic", "node", "component", "part"),
            _parts(q),
            {"units": "m (translations), rad (rotations)", "long_name": "two-sided q_n"},
        ),
        "position": (
            ("node", "xyz"),
            np.array([point.positions.get(k, np.zeros(3)) for k in nodes]),
            {"units": "m"},
        ),
    }
    names = list(a.joints)
    if names:
        F = np.array([bearing_force_array(sol, a, j)[1] for j in names])
        coords["bearing"] = ("bearing", names)
        data["bearing_force"] = (
            ("bearing", "harmonic", "force_component", "part"),
            _parts(F),
            {"units": "N (forces), N m (moments)", "long_name": "force on the support"},
        )
    meshes = list(a.meshes)
    if meshes:
        E = np.array([transmission_error_array(sol, a, m)[1] for m in meshes])
        coords["mesh"] = ("mesh", meshes)
        data["dte"] = (
            ("mesh", "harmonic", "part"),
            _parts(E),
            {"units": "m", "long_name": "dynamic transmission error (line of action)"},
        )
    hist = np.asarray(sol.history, dtype=float)
    data["residual_history"] = (("iteration",), hist, {"units": "1"})
    coords["iteration"] = ("iteration", np.arange(1, hist.size + 1))
    ds = xr.Dataset(data, coords=coords)
    ds.attrs["markers_json"] = json.dumps(frequency_markers(a))
    if a.frames is not None and a.frames.planets():
        ds.attrs["orbits_json"] = json.dumps(orbit_frequencies(a))
    ds.attrs.update(
        {
            "title": f"rheolin steady state{': ' + model_name if model_name else ''}",
            "rheolin_version": __version__,
            "speed": a.speed,
            "speed_units": "rad/s",
            "speed_rpm": significant(a.speed * 30 / math.pi),
            "base_frequency": a.omega,
            "base_frequency_units": "rad/s",
            "method": sol.method,
            "requested_method": str(point.settings.get("method", "")),
            "success": int(sol.success),
            "status": int(sol.status),
            "message": sol.message,
            "iterations": int(sol.iterations),
            "residual": float(sol.residual),
            "residual_kind": "backward error ||f - A q|| / (||A|| ||q|| + ||f||)",
            "relative_residual": float(sol.info.get("relative_residual", float("nan"))),
            "rtol": float(point.settings.get("rtol", float("nan"))),
            "stability": stability_text(
                sol.stable,
                None if sol.floquet is None else bool(sol.floquet.decided),
                sol.max_floquet_real,
                None if sol.floquet is None else leading_tolerance(sol.floquet),
            ),
            "max_floquet_real": float("nan")
            if sol.max_floquet_real is None
            else float(sol.max_floquet_real),
            **floquet_attrs(sol),
            "harmonic_count": len(sol.harmonics),
            "closure_order": int(point.settings.get("order", 0)),
            "max_order": float(point.settings.get("max_order") or 0.0),
            "n_dof": int(a.system.n),
            "model_sha256": model_sha256,
            "solve_seconds": float(point.seconds),
            "convention": "x(t) = sum_n x_n exp(i n w1 t); stored n >= 0; amplitude 2|x_n|",
        }
    )
    return ds


def netcdf_engine() -> str:
    """``"h5netcdf"`` (NetCDF4) when its HDF5 backend ``h5py`` is importable, else ``"scipy"``
    (NetCDF3; integers stored as int32)."""
    try:
        import h5netcdf  # noqa: F401
        import h5py  # noqa: F401
    except ImportError:
        return "scipy"
    return "h5netcdf"


def frequency_markers(a: Assembled) -> dict[str, float]:
    """Named frequencies [Hz] for plots: each shaft's speed (1x) and each mesh frequency."""
    planets = set() if a.frames is None else set(a.frames.planets())
    out = {
        f"{b} 1x": abs(s) * a.omega / (2 * math.pi)
        for b, s in a.plan.spin.items()
        if s and b not in planets
    }
    for name, (_, _, n) in a.meshes.items():
        label = name.split(".")[0] if name.split(".")[0] in a.plan.sets else name  # one per set
        out[f"{label} mesh"] = abs(n) * a.omega / (2 * math.pi)
    return out


def orbit_frequencies(a: Assembled) -> dict[str, float]:
    """Each planet's orbit frequency [Hz], its carrier's speed (for the orbit plots)."""
    if a.frames is None:
        return {}
    out = {}
    for name, (_, spin, _) in a.frames.sets.items():
        for planet in a.frames.planets():
            if planet.startswith(f"{name}.planet"):
                out[planet] = abs(spin) * a.omega / (2 * math.pi)
    return out


def write_dataset(ds: xr.Dataset, path: str | Path) -> Path:
    """Write NetCDF atomically: temporary file, then rename (see :func:`netcdf_engine`); the
    units of the names :data:`~rheolin.results.units.UNITS` knows filled where missing."""
    engine = netcdf_engine()
    out = with_units(ds)
    if engine == "scipy":  # NetCDF3 has no int64
        for name, var in list(out.variables.items()):
            if var.dtype == np.int64:
                out[name] = var.astype(np.int32)
    with atomic_write(path) as tmp:
        out.to_netcdf(tmp, engine=engine)  # type: ignore[call-overload]
    return Path(path)
