"""The unit convention of rheolin's result files (docs/results-schema.md, "Units").

* SI everywhere. A rotational speed is in rad/s (``speed``, ``critical_speed``,
  ``range_lower``); its value in rpm, where a file adds it for reading, is named ``*_rpm``.
* A variable named ``frequency`` (or ``*_frequency``, ``*_offset`` of frequencies) is in Hz;
  an angular frequency in rad/s is named so (``base_frequency_rad_s``, ``angular_*``).
* Every numeric variable and coordinate has a ``units`` attribute (``"1"`` for ratios,
  counts, flags and indices); a numeric attribute of a file names its unit in its name
  (``speed_rad_s``, ``solve_seconds``) or in ``<name>_units``.
* Complex values are two-sided coefficients on a trailing ``part = [real, imag]`` axis;
  :func:`~rheolin.results.dataset.complex_amplitude` gives the single-sided complex amplitude.

:func:`with_units` fills the units of the names below where a writer left them out (it never
changes a unit a writer set); :func:`missing_units` lists what still has none.

>>> import numpy as np, xarray as xr
>>> ds = xr.Dataset({"stable": ("speed", [1, 0]), "max_real": ("speed", [-1.0, 0.5])},
...                 coords={"speed": [100.0, 200.0]})
>>> missing_units(ds)
['max_real', 'speed', 'stable']
>>> missing_units(with_units(ds)), with_units(ds)["max_real"].attrs["units"]
([], '1/s')
>>> significant(1500.0000000000002), significant(999.9999999999999)
(1500.0, 1000.0)
"""

from __future__ import annotations

import math
from typing import Any

import xarray as xr

from ..io.units import significant

__all__ = ["UNITS", "missing_units", "significant", "speed_attrs", "with_units"]

_ONE = (
    "success status iterations stable decided marginal converged range_lower_open "
    "range_upper_open harmonic node_index iteration mode sideband critical_mode residual "
    "relative_residual whirl_ratio damping_ratio log_decrement energy_share order_ratio order "
    "shape points failed resumed computed"
).split()

#: Units of the names rheolin's files use, where the writer sets none.
UNITS: dict[str, str] = {
    **dict.fromkeys(_ONE, "1"),
    **dict.fromkeys(
        (
            "max_real",
            "tol",
            "max_floquet_real",
            "map_max_real",
            "range_max_real",
            "max_real_uncertainty",
            "max_floquet_real_uncertainty",
        ),
        "1/s",
    ),
    **dict.fromkeys(("seconds", "solve_seconds", "floquet_seconds"), "s"),
    **dict.fromkeys(
        (
            "speed",
            "range_lower",
            "range_upper",
            "range_lower_uncertainty",
            "range_upper_uncertainty",
            "critical_speed",
        ),
        "rad/s",
    ),
    **dict.fromkeys(
        ("speed_rpm", "critical_speed_rpm", "range_lower_rpm", "range_upper_rpm"), "rpm"
    ),
    **dict.fromkeys(("frequency", "critical_frequency", "sideband_offset"), "Hz"),
    **dict.fromkeys(("position", "response", "dte"), "m"),
    "stiffness": "N/m",
}


def _numeric(da: xr.DataArray) -> bool:
    return da.dtype.kind in "fiubc"


def with_units(ds: xr.Dataset) -> xr.Dataset:
    """A copy of ``ds`` in which every variable and coordinate named in :data:`UNITS` that
    has no ``units`` attribute gets one."""
    out = ds.copy()
    for name in list(out.variables):
        var = out.variables[name]
        if "units" not in var.attrs and str(name) in UNITS and _numeric(out[name]):
            var.attrs["units"] = UNITS[str(name)]
    return out


def missing_units(ds: xr.Dataset) -> list[str]:
    """Numeric variables and coordinates of ``ds`` without a ``units`` attribute, sorted."""
    return sorted(
        str(n) for n in ds.variables if _numeric(ds[n]) and "units" not in ds.variables[n].attrs
    )


def speed_attrs(speed_rad_s: float) -> dict[str, Any]:
    """``speed_rad_s`` and its rounded ``speed_rpm``, for a file's attributes."""
    return {"speed_rad_s": float(speed_rad_s), "speed_rpm": significant(speed_rad_s * 30 / math.pi)}
