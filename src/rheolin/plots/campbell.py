"""Campbell diagram plot: frequencies and damping of the averaged modes against speed."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.cm import ScalarMappable
from matplotlib.colors import LinearSegmentedColormap, Normalize
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ._common import hatch_undecided, new_figure, save

__all__ = ["campbell_figure", "critical_map_figure", "plot_campbell", "plot_critical_map"]

RPM = 60.0 / (2.0 * np.pi)  # rad/s -> rpm
HZ = 1.0 / (2.0 * np.pi)  # rad/s -> Hz
#: Whirl ratio -1 (backward) red, 0 (planar, none) white, +1 (forward) blue.
WHIRL_MAP = LinearSegmentedColormap.from_list("whirl", ["#d62728", "#f7f7f7", "#1f77b4"])
#: Markers by the mode's kind (its first word), and their legend label ("": lateral).
_MARKERS = {
    "": ("o", ""),
    "torsional": ("s", "torsional"),
    "axial": ("^", "axial"),
    "coupled": ("D", "coupled"),
}


def _order_styles(names: list[str]) -> dict[str, tuple[str, str]]:
    """Colour and dash of each order line: mesh orders in reds, each shaft's 1x (dashed) and
    2x (dotted) in one shade of grey."""
    shades = ("0.1", "0.4", "0.6", "0.25", "0.5")
    reds = ("tab:red", "darkred", "salmon", "firebrick")
    bodies = list(dict.fromkeys(n.split(" ", 1)[1] for n in names if not n.startswith("mesh")))
    out, meshes = {}, 0
    for n in names:
        if n.startswith("mesh"):
            out[n] = (reds[meshes % len(reds)], "-." if meshes % 2 else "--")
            meshes += 1
        else:
            shade = shades[bodies.index(n.split(" ", 1)[1]) % len(shades)]
            out[n] = (shade, ":" if n.startswith("2x") else "--")
    return out


def campbell_figure(result: Any, fmax_hz: float | None = None, stability: Any = None) -> Figure:
    """The Campbell diagram (see :func:`plot_campbell`) as a Figure."""
    fig, axes = new_figure(2, 1, (10, 9))
    ax, axd = axes[0, 0], axes[1, 0]
    rpm = np.asarray(result.speeds) * RPM
    freq = np.asarray(result.frequency) * HZ
    ratio = np.nan_to_num(np.asarray(result.whirl_ratio, dtype=float))
    kinds = np.asarray(result.kind if result.kind is not None else np.full(freq.shape, ""), str)
    first = np.char.partition(kinds, " ")[..., 0]
    fmax = _default_fmax(freq, result) if fmax_hz is None else float(fmax_hz)
    below = np.nanmin(np.where(np.isfinite(freq), freq, np.inf), axis=0) <= fmax
    zeta = np.asarray(result.damping_ratio)
    speeds = np.broadcast_to(rpm[:, None], freq.shape)
    norm = Normalize(-1.0, 1.0)
    shapes = []
    for shape, (marker, name) in _MARKERS.items():
        mask = np.isfinite(freq) & below[None, :]
        mask &= (first == shape) if shape else ~np.isin(first, [k for k in _MARKERS if k])
        if not mask.any():
            continue
        for a, y in ((ax, freq), (axd, zeta)):
            a.scatter(
                speeds[mask],
                y[mask],
                c=ratio[mask],
                cmap=WHIRL_MAP,
                norm=norm,
                marker=marker,
                s=16,
                lw=0.3,
                edgecolors="0.2",
                zorder=3,
            )
        shapes.append(
            Line2D([], [], marker=marker, ls="", mfc="white", mec="k", label=name or "lateral")
        )
    for j in np.flatnonzero(below):
        ax.plot(rpm, freq[:, j], "-", lw=0.6, color="0.75", zorder=1)
        axd.plot(rpm, zeta[:, j], "-", lw=0.6, color="0.75", zorder=1)
    lines = []
    styles = _order_styles(list(result.orders))
    for name, r in result.orders.items():
        color, dash = styles[name]
        lines += ax.plot(
            rpm, r * np.asarray(result.speeds) * HZ, dash, lw=1.0, color=color, label=name, zorder=2
        )
    for c in result.critical_speeds:
        if c.frequency * HZ <= fmax:
            face = "none" if c.whirl != "forward" else "gold"
            ax.plot(
                c.speed * RPM,
                c.frequency * HZ,
                "o",
                ms=10,
                mfc=face,
                mec="k",
                mew=1.0,
                alpha=0.8,
                zorder=4,
            )
    shapes.append(
        Line2D(
            [], [], marker="o", ls="", ms=9, mfc="gold", mec="k", label="critical speed (forward)"
        )
    )
    shapes.append(
        Line2D([], [], marker="o", ls="", ms=9, mfc="none", mec="k", label="critical speed (other)")
    )
    ax.set_ylim(0.0, fmax)
    for a in (ax, axd):
        a.set_xlim(rpm[0], rpm[-1])
        a.set_xlabel("input speed [rpm]")
        a.grid(alpha=0.3)
    undecided = np.zeros(0, dtype=bool)
    if stability is not None:
        for r in stability.ranges:
            for a in (ax, axd):
                a.axvspan(r.lower * RPM, r.upper * RPM, color="tab:red", alpha=0.12, lw=0)
        undecided = np.asarray(stability.undecided, dtype=bool)
        hatch_undecided([ax, axd], np.asarray(stability.speeds) * RPM, undecided)
    ax.set_ylabel("damped natural frequency [Hz]")
    title = "Campbell diagram (time-averaged system)"
    if stability is not None:
        parts = []
        if stability.ranges:
            parts.append(f"{len(stability.ranges)} unstable range(s), shaded")
        if undecided.any():
            parts.append(f"{int(undecided.sum())} speed(s) undecided, hatched")
        title += "; Floquet: " + (", ".join(parts) if parts else "stable at every speed")
    ax.set_title(title, fontsize=10)
    fig.legend(
        handles=shapes, fontsize=7, loc="outside right upper", title="mode kind", title_fontsize=7
    )
    fig.legend(
        handles=lines, fontsize=7, loc="outside right lower", title="order lines", title_fontsize=7
    )
    fig.colorbar(
        ScalarMappable(norm=norm, cmap=WHIRL_MAP),
        ax=[ax, axd],
        location="bottom",
        shrink=0.5,
        label="whirl ratio: +1 forward, -1 backward, 0 planar or none",
    )
    finite = zeta[:, below][np.isfinite(zeta[:, below])]
    if finite.size == 0 or np.abs(finite).max() < 1e-9:  # undamped: rounding noise only
        axd.set_ylim(-0.01, 0.01)
        axd.set_title("damping ratio: undamped (|damping ratio| < 1e-9)", fontsize=10)
    else:
        axd.set_title(
            f"damping ratio of the {int(below.sum())} branches below {fmax:.0f} Hz "
            "(negative: a growing mode)",
            fontsize=10,
        )
    axd.axhline(0.0, color="tab:red", lw=1.0)
    axd.set_ylabel("damping ratio [-]")
    return fig


def plot_campbell(
    result: Any, path: str | Path, fmax_hz: float | None = None, stability: Any = None
) -> Path:
    """Campbell diagram as a PNG.

    Top: damped natural frequencies [Hz] against input speed [rpm], one marker per mode and
    speed, coloured by the whirl ratio (+1 forward blue, -1 backward red, 0 planar or no
    whirl white) and shaped by kind (circles lateral, squares torsional, triangles axial,
    diamonds coupled); order lines in their own legend, critical speeds circled (filled for
    forward whirl). Bottom: damping ratio of the same branches (a negative value is a
    growing mode of the averaged system).

    Parameters
    ----------
    result
        A :class:`~rheolin.stability.CampbellResult`.
    path
        PNG file to write.
    fmax_hz
        Upper frequency limit [Hz]. Default: 1.25 times the highest order line at the top
        speed (at least up to the two lowest branches), so that the crossings are readable
        and far, speed-independent modes (axial, torsional, housing) do not flatten them.
        The damping panel shows the branches below this limit.
    stability
        A :class:`~rheolin.stability.StabilityMap` over the same speeds: its unstable ranges
        (of the full time-periodic system, Floquet) are shaded in both panels.

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib
    >>> from rheolin.stability import CampbellResult
    >>> W = np.linspace(10.0, 100.0, 4)
    >>> r = CampbellResult(W, np.tile([50.0, 60.0], (4, 1)), np.full((4, 2), 0.01),
    ...                    np.full((4, 2), 0.06), np.tile([1.0, -1.0], (4, 1)), {"1x s": 1.0})
    >>> p = plot_campbell(r, pathlib.Path(tempfile.mkdtemp()) / "c.png")
    >>> p.stat().st_size > 1000
    True
    """
    return save(campbell_figure(result, fmax_hz, stability), path)


def _default_fmax(freq: np.ndarray, result: Any) -> float:
    if not np.isfinite(freq).any():
        return 1.0
    top = float(np.nanmax(freq))
    lines = [r * float(np.max(result.speeds)) * HZ for r in result.orders.values()]
    if not lines:
        return top * 1.08
    lowest = np.sort(np.nanmax(np.where(np.isfinite(freq), freq, np.nan), axis=0))
    floor = float(lowest[min(1, lowest.size - 1)]) * 1.1
    return min(top * 1.08, max(1.25 * max(lines), floor))


def plot_critical_map(result: Any, path: str | Path) -> Path:
    """Undamped critical-speed map as a PNG (:func:`critical_map_figure`).

    >>> import numpy as np, tempfile, pathlib
    >>> from rheolin.stability.critical_map import CriticalSpeedMap
    >>> k = np.logspace(5, 9, 9)
    >>> r = CriticalSpeedMap(k, np.column_stack([np.sqrt(k / 20), 300 + 0 * k]), ["b"], {"b": 1e7})
    >>> plot_critical_map(r, pathlib.Path(tempfile.mkdtemp()) / "m.png").stat().st_size > 1000
    True
    """
    return save(critical_map_figure(result), path)


def critical_map_figure(result: Any) -> Figure:
    """Critical speeds [rpm] against bearing stiffness [N/m], log-log, one line per critical
    speed; each bearing's own stiffness dashed."""
    fig, axes = new_figure(1, 1, (8, 6))
    ax = axes[0, 0]
    k = np.asarray(result.stiffness)
    rpm = np.asarray(result.speeds) * RPM
    for j in range(rpm.shape[1]):
        if np.any(np.isfinite(rpm[:, j])):
            ax.loglog(k, rpm[:, j], "-o", ms=3, lw=1.4, label=f"critical speed {j + 1}")
    seen: set[float] = set()
    for name, value in result.actual.items():
        if value > 0 and round(value, 3) not in seen:
            seen.add(round(value, 3))
            ax.axvline(value, color="0.3", ls="--", lw=0.9)
            ax.annotate(
                f"{name}: {value:.3g} N/m",
                (value, 0.02),
                xycoords=("data", "axes fraction"),
                rotation=90,
                fontsize=7,
                ha="right",
                va="bottom",
                color="0.3",
            )
    ax.set_xlabel("bearing stiffness [N/m] (isotropic, every bearing varied)")
    ax.set_ylabel("undamped critical speed [rpm]")
    ax.set_title("undamped critical-speed map (forward synchronous whirl)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    return fig
