"""One chunk of a study: the points one task computed, as an ``xarray.Dataset`` over ``point``.

A chunk file is a NetCDF file that ``xarray.open_dataset`` reads on its own:

* ``point`` (global point number, see :class:`~rheolin.study.spec.StudySpec`) and ``speed``;
* amplitudes ``response(point, harmonic, node)``, ``bearing_force(point, bearing, harmonic)``,
  ``dte(point, mesh, harmonic)`` (as in ``sweep.nc``);
* per point ``success``, ``status``, ``iterations``, ``residual``, ``stable`` (1/0/-1/-2:
  :data:`~rheolin.results.sweep.STABILITY_FLAGS`), ``max_floquet_real`` and
  ``max_floquet_real_uncertainty``, ``method``, ``message``, ``seconds``;
* the Floquet result of each point, pickled (:class:`~rheolin.FloquetResult`, to rebuild the
  stability map on resume): bytes ``floquet_offset[i] : floquet_offset[i] + floquet_size[i]``
  of ``floquet_pickle(byte)`` (size 0: not computed). Read them with :func:`floquet_results`;
  unpickling runs code, so only open checkpoints you wrote.

Attributes: ``study_key``, ``w1_per_speed`` (base frequency / input speed) and
``marker_orders_json`` (shaft and mesh orders for plots).
"""

from __future__ import annotations

import json
import math
import pickle
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from ..results.compute import OperatingPoint
from ..results.dataset import frequency_markers, netcdf_engine, write_dataset
from ..results.sweep import floquet_uncertainty, point_amplitudes, stability_flag

#: Coordinates a chunk keeps (frequency and order follow from speed and harmonic).
_KEEP = ("harmonic", "node", "body", "bearing", "mesh")

__all__ = ["chunk_dataset", "floquet_results", "point_row", "read_chunk", "write_chunk"]


def point_row(p: OperatingPoint, floquet: Any, seconds: float) -> xr.Dataset:
    """One computed point as a Dataset without the ``point`` dimension."""
    s = p.solution
    data: dict[str, Any] = {}
    amps = point_amplitudes(p)
    for key, units in (("response", "m"), ("bearing_force", "N"), ("dte", "m")):
        if key in amps:
            data[key] = amps[key].assign_attrs(units=units, long_name=f"{key} amplitude")
    scalars = {
        "success": int(s.success),
        "status": int(s.status),
        "iterations": int(s.iterations),
        "residual": float(s.residual),
        "stable": stability_flag(s.stable, floquet),
        "max_floquet_real": np.nan if s.max_floquet_real is None else float(s.max_floquet_real),
        "max_floquet_real_uncertainty": floquet_uncertainty(floquet)
        if s.stable is not None
        else np.nan,
        "method": str(s.method),
        "message": str(s.message),
        "seconds": float(seconds),
    }
    scalars["speed"] = float(p.assembled.speed)
    ds = xr.Dataset({**data, **{key: ((), value) for key, value in scalars.items()}})
    ds = ds.drop_vars([c for c in ds.coords if c not in _KEEP])
    blob = b"" if floquet is None else pickle.dumps(floquet, protocol=pickle.HIGHEST_PROTOCOL)
    ds.attrs["floquet"] = blob  # moved into floquet_pickle by chunk_dataset
    a = p.assembled
    orders = {k: v / (a.speed / (2 * math.pi)) for k, v in frequency_markers(a).items()}
    ds.attrs["marker_orders_json"] = json.dumps(orders)
    ds.attrs["w1_per_speed"] = float(a.base_ratio)
    return ds


def chunk_dataset(points: list[int], rows: list[xr.Dataset], key: str) -> xr.Dataset:
    """Stack the rows of ``points`` (aligned on harmonics, nodes, bearings, meshes)."""
    blobs = [r.attrs.pop("floquet") for r in rows]
    attrs = dict(rows[0].attrs)
    ds = xr.concat(rows, dim="point", join="outer", coords="different", compat="equals")
    ds = ds.assign_coords(point=("point", np.asarray(points, dtype=np.int64)))
    ds = ds.set_coords("speed")
    sizes = np.array([len(b) for b in blobs], dtype=np.int64)
    ds["floquet_size"] = ("point", sizes)
    ds["floquet_offset"] = ("point", np.concatenate([[0], np.cumsum(sizes)[:-1]]))
    ds["floquet_pickle"] = ("byte", np.frombuffer(b"".join(blobs), dtype=np.uint8))
    ds.attrs = {**attrs, "study_key": key}
    return ds


def floquet_results(ds: xr.Dataset) -> dict[int, Any]:
    """``{point: FloquetResult}`` of a chunk (points without a result left out)."""
    raw = ds["floquet_pickle"].values.tobytes()
    out = {}
    for point, start, size in zip(
        ds["point"].values, ds["floquet_offset"].values, ds["floquet_size"].values, strict=True
    ):
        if size > 0:
            out[int(point)] = pickle.loads(raw[int(start) : int(start) + int(size)])
    return out


def write_chunk(ds: xr.Dataset, path: Path) -> Path:
    """Write a chunk file atomically (temporary file, fsync, rename)."""
    return write_dataset(ds, path)


def read_chunk(path: Path) -> xr.Dataset:
    """Read a whole chunk file into memory (and close it)."""
    with xr.open_dataset(path, engine=netcdf_engine()) as ds:
        return ds.load()
