"""Plots of a parameter study: an output over speed and one parameter, and the unstable
ranges against that parameter."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
from matplotlib.cm import ScalarMappable
from matplotlib.colors import LogNorm, Normalize
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ._common import new_figure, save

__all__ = ["QUANTITIES", "parameter_figure", "parameter_plot", "study_quantity"]

#: Outputs that :func:`parameter_plot` can show: variable, reduction, label, scale.
QUANTITIES = {
    "response": ("node", "largest radial dynamic response (sum of harmonics) [µm]", 1e6),
    "bearing_force": (
        "bearing",
        "largest radial dynamic bearing force (sum of harmonics) [N]",
        1.0,
    ),
    "dte": ("mesh", "largest dynamic transmission error (sum of harmonics) [µm]", 1e6),
    "max_floquet_real": ("", "largest Floquet real part [1/s]", 1.0),
}
#: Up to this many values a parameter is drawn as curves, above as a heat map.
LINES = 12
_COLOURS = {
    "asymmetric shaft band": "tab:red",
    "parametric mesh resonance": "tab:purple",
    "combined parametric excitation": "tab:orange",
    "rotating damping": "tab:brown",
    "circulatory forces (time-invariant)": "tab:pink",
}


def study_quantity(ds: Any, quantity: str) -> Any:
    """The output over ``(*parameters, speed)``: the sum over the oscillating harmonics of
    the amplitudes, the largest over nodes (bearings, meshes), in the units of
    :data:`QUANTITIES`; or the largest Floquet real part."""
    if quantity not in QUANTITIES:
        raise ValueError(f"`quantity` must be one of {sorted(QUANTITIES)}, got {quantity!r}")
    over, _, scale = QUANTITIES[quantity]
    if not over:
        name = "map_max_real" if "map_max_real" in ds else "max_floquet_real"
        return ds[name]
    if quantity not in ds:
        raise ValueError(f"the results have no {quantity!r} (the model has no {over})")
    amp = ds[quantity].where(ds["harmonic"] > 0, 0.0).sum("harmonic", min_count=1)
    return amp.max(over) * scale


def parameter_plot(result: Any, path: str, file: str | Path, quantity: str = "response") -> Path:
    """One parameter of a study as a PNG (:func:`parameter_figure`)."""
    return save(parameter_figure(result, path, quantity), file)


def parameter_figure(result: Any, path: str, quantity: str = "response") -> Figure:
    """One parameter of a study: top, ``quantity`` over speed and the parameter (colour;
    unstable points crossed, failed points grey); bottom, when there are any, the unstable
    speed ranges of every value of the parameter, coloured by mechanism (else the title says
    that there are none). Other parameters are held at their middle value (said in the
    title).

    ``result`` is a :class:`~rheolin.study.StudyResult`.
    """
    spec = result.spec
    ds = result.dataset
    sds = result.stability_dataset() if result.maps else None
    if sds is not None and "map_max_real" not in ds:
        ds = ds.assign(map_max_real=sds["max_real"].reindex(speed=spec.speeds))
    p = {q.path: q for q in spec.parameters}[path]
    fixed = {q.path: len(q.values) // 2 for q in spec.parameters if q.path != path}
    sel = ds.isel(fixed)
    z = study_quantity(sel, quantity).transpose(path, "speed").values.astype(float)
    rpm = spec.speeds * 30 / np.pi
    y = np.asarray(p.values, dtype=float)
    unstable = sel["stable"].transpose(path, "speed").values == 0
    if sds is not None:  # the map's verdict (also when the per-point check is off)
        verdict = sds["stable"].reindex(speed=spec.speeds).isel(fixed)
        unstable |= verdict.transpose(path, "speed").values.astype(float) == 0
    failed = sel["status"].transpose(path, "speed").values < 0
    ranges = _ranges_of(result, spec, path, fixed)
    if ranges:
        fig, axes = new_figure(2, 1, (9, 9.5))
        ax, rg = axes[0, 0], axes[1, 0]
    else:  # nothing to draw below: the verdict goes into the title
        fig, axes = new_figure(1, 1, (9, 5.8))
        ax, rg = axes[0, 0], None
    log = quantity != "max_floquet_real"
    unit = f" [{p.unit}]" if p.unit else ""
    if y.size <= LINES:
        _lines(fig, ax, rpm, y, z, unstable, failed, log, quantity, f"{path}{unit}")
    else:
        _heat_map(fig, ax, rpm, y, z, unstable, failed, log, quantity)
        ax.set_ylabel(f"{path}{unit}")
    ax.set_xlabel("input speed [rpm]")
    wide = y.size > 1 and y.min() > 0 and y.max() / y.min() > 20
    if wide and y.size > LINES:
        ax.set_yscale("log")
    held = ", ".join(spec.parameters[i].describe(j) for i, j in _held(spec, fixed))
    what = QUANTITIES[quantity][1].split(" [")[0]
    title = f"{what}\nover speed and {path}" + (f" ({held})" if held else "")
    if rg is None:
        title += "\n" + (
            "stability map not computed" if not result.maps else "no unstable range at any value"
        )
    ax.set_title(title, fontsize=10)
    if rg is not None:
        rg.set_ylabel(f"{path}{unit}")
        rg.set_xlabel("input speed [rpm]")
        if wide:
            rg.set_yscale("log")
        _ranges(rg, ranges, y, rpm)
    return fig


def _lines(
    fig: Any,
    ax: Any,
    rpm: Any,
    y: Any,
    z: Any,
    unstable: Any,
    failed: Any,
    log: bool,
    q: str,
    name: str,
) -> None:
    """One curve per parameter value (a waterfall), coloured by the value."""
    cmap = matplotlib.colormaps["viridis"]
    norm = Normalize(y.min(), y.max()) if y.size > 1 else Normalize(y[0] - 1, y[0] + 1)
    for k, value in enumerate(y):
        ax.plot(rpm, z[k], "o-", ms=3, lw=1.2, color=cmap(norm(value)))
        ax.plot(rpm[unstable[k]], z[k][unstable[k]], "x", color="tab:red", ms=7, mew=1.5)
    if log and np.any(z > 0):
        ax.set_yscale("log")
    ax.set_ylabel(QUANTITIES[q][1], fontsize=9)
    fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=fig.axes[:2], label=name)
    ax.grid(alpha=0.3, which="both")
    _legend(ax, unstable, failed)


def _heat_map(
    fig: Any, ax: Any, rpm: Any, y: Any, z: Any, unstable: Any, failed: Any, log: bool, q: str
) -> None:
    """The output as colour over (speed, parameter)."""
    finite = z[np.isfinite(z)]
    positive = finite[finite > 0]
    log = log and positive.size > 0
    norm: Any = LogNorm(positive.min(), positive.max()) if log else Normalize(*_limits(finite))
    values = np.where(z > 0, z, np.nan) if log else z
    mesh = ax.pcolormesh(
        rpm, y, values, shading="nearest", norm=norm, cmap="viridis" if log else "coolwarm"
    )
    fig.colorbar(mesh, ax=fig.axes[:2], label=QUANTITIES[q][1])
    yy, xx = np.meshgrid(y, rpm, indexing="ij")
    ax.plot(xx[unstable], yy[unstable], "x", color="tab:red", ms=5)
    ax.plot(xx[failed], yy[failed], "s", color="0.5", ms=5)
    _legend(ax, unstable, failed)


def _legend(ax: Any, unstable: Any, failed: Any) -> None:
    handles = []
    if unstable.any():
        handles.append(Line2D([], [], ls="", marker="x", color="tab:red", label="unstable"))
    if failed.any():
        handles.append(Line2D([], [], ls="", marker="s", color="0.5", label="failed (no result)"))
    if handles:
        ax.legend(handles=handles, fontsize=8, loc="upper right")


def _ranges_of(result: Any, spec: Any, path: str, fixed: dict[str, int]) -> list[tuple[float, Any]]:
    """The unstable ranges of every value of parameter ``path`` (the others held at
    ``fixed``): ``(value, range)`` pairs."""
    index = [q.path for q in spec.parameters].index(path)
    out = []
    for combo, smap in sorted(result.maps.items()):
        at = {q.path: i for q, i in spec.assignments(combo)}
        if any(at[k] != v for k, v in fixed.items()):
            continue
        yv = spec.parameters[index].values[at[path]]
        out += [(yv, r) for r in smap.ranges]
    return out


def _ranges(ax: Any, ranges: list[tuple[float, Any]], y: np.ndarray, rpm: Any) -> None:
    """Unstable ranges (bars) against the parameter, coloured by mechanism."""
    step = np.diff(y).min() if y.size > 1 else 1.0
    height = 0.6 * step
    seen: set[str] = set()
    for yv, r in ranges:
        lo, hi = r.lower * 30 / np.pi, r.upper * 30 / np.pi
        colour = _COLOURS.get(r.mechanism, "0.3")
        label = r.mechanism if r.mechanism not in seen else None
        seen.add(r.mechanism)
        if ax.get_yscale() == "log":
            ax.fill_between(
                [lo, hi], yv / 1.08, yv * 1.08, color=colour, alpha=0.6, label=label, lw=0
            )
        else:
            ax.barh(yv, hi - lo, left=lo, height=height, color=colour, alpha=0.6, label=label)
    ax.set_xlim(rpm[0], rpm[-1])
    if y.size and ax.get_yscale() != "log":
        ax.set_ylim(y.min() - 0.5 * step, y.max() + 0.5 * step)
    ax.grid(alpha=0.3)
    ax.set_title(f"unstable speed ranges ({len(ranges)}), by mechanism", fontsize=10)
    ax.legend(fontsize=8, loc="upper right")


def _held(spec: Any, fixed: dict[str, int]) -> list[tuple[int, int]]:
    paths = [q.path for q in spec.parameters]
    return [(paths.index(k), v) for k, v in fixed.items()]


def _limits(values: np.ndarray) -> tuple[float, float]:
    if values.size == 0:
        return -1.0, 1.0
    m = float(np.abs(values).max()) or 1.0
    return -m, m
