"""Campbell diagram plot: frequencies and damping of the averaged modes against speed."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ._common import new_figure, save

__all__ = ["plot_campbell", "plot_critical_map"]

RPM = 60.0 / (2.0 * np.pi)  # rad/s -> rpm
HZ = 1.0 / (2.0 * np.pi)  # rad/s -> Hz
_COLORS = {"forward": "tab:blue", "backward": "tab:red", "mixed": "tab:purple", "none": "0.45"}
#: Markers by the mode's kind (its first word), and their legend label ("" : by whirl).
_MARKERS = {
    "": ("o", ""),
    "torsional": ("s", "torsional"),
    "axial": ("^", "axial"),
    "coupled": ("D", "coupled"),
}


def plot_campbell(
    result: Any, path: str | Path, fmax_hz: float | None = None, stability: Any = None
) -> Path:
    """Campbell diagram as a PNG.

    Top: damped natural frequencies [Hz] against input speed [rpm], one marker per mode and
    speed, coloured by whirl (forward blue, backward red, mixed purple, no whirl grey), shaped
    by kind (circles lateral, squares torsional, triangles axial, diamonds coupled); order
    lines dashed (mesh orders red) and critical speeds circled (filled for forward whirl).
    Bottom: damping ratio of every branch (a negative value is a growing mode of the
    averaged system).

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
        (of the full time-periodic system, Floquet) are shaded in both panels and labelled.

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
    fig, axes = new_figure(2, 1, (9, 8.5))
    ax, axd = axes[0, 0], axes[1, 0]
    rpm = np.asarray(result.speeds) * RPM
    freq = np.asarray(result.frequency) * HZ
    labels = np.asarray(result.whirl)
    kinds = np.asarray(result.kind if result.kind is not None else np.full(freq.shape, ""), str)
    shown = set()
    for kind, color in _COLORS.items():
        for shape, (marker, name) in _MARKERS.items():
            mask = (labels == kind) & np.char.startswith(kinds, shape)
            if shape == "":
                mask = (labels == kind) & ~np.isin(
                    np.char.partition(kinds, " ")[..., 0], [k for k in _MARKERS if k]
                )
            if not mask.any():
                continue
            speeds = np.broadcast_to(rpm[:, None], freq.shape)[mask]
            label = name or ("no whirl" if kind == "none" else f"{kind} whirl")
            ax.plot(speeds, freq[mask], marker, ms=3.5, color=color, ls="none",
                    label=None if label in shown else label)  # fmt: skip
            shown.add(label)
    for j in range(freq.shape[1]):
        ax.plot(rpm, freq[:, j], "-", lw=0.6, color="0.7", zorder=0)
    fmax = _default_fmax(freq, result) if fmax_hz is None else float(fmax_hz)
    for name, ratio in result.orders.items():
        line = ratio * np.asarray(result.speeds) * HZ
        color = "tab:red" if name.startswith("mesh") else "k"
        ax.plot(rpm, line, "--", lw=0.9, color=color, alpha=0.6)
        inside = np.nonzero(line <= fmax)[0]
        if inside.size:
            i = inside[-1]
            ax.annotate(
                name,
                (rpm[i], line[i]),
                fontsize=7,
                color=color,
                xytext=(2, 2),
                textcoords="offset points",
            )
    for c in result.critical_speeds:
        face = _COLORS.get(c.whirl, "0.45") if c.whirl == "forward" else "none"
        ax.plot(c.speed * RPM, c.frequency * HZ, "o", ms=9, mfc=face, mec="k", mew=1.0, alpha=0.8)
    ax.set_ylim(0.0, fmax)
    ax.set_xlim(rpm[0], rpm[-1])
    if stability is not None:
        for r in stability.ranges:
            for a in (ax, axd):
                a.axvspan(r.lower * RPM, r.upper * RPM, color="tab:red", alpha=0.12, lw=0)
            ax.annotate(
                f"unstable (Floquet): {r.label}"[:90],
                (0.5 * (r.lower + r.upper) * RPM, 0.97 * fmax),
                ha="center",
                va="top",
                fontsize=7,
                color="tab:red",
            )
    ax.set_xlabel("input speed [rpm]")
    ax.set_ylabel("damped natural frequency [Hz]")
    title = "Campbell diagram (time-averaged system); circles: critical speeds"
    if stability is not None:
        title += "\n" + (
            f"Floquet: {len(stability.ranges)} unstable range(s) shaded"
            if stability.ranges
            else "Floquet: stable at every speed"
        )
    ax.set_title(title)
    ax.grid(alpha=0.3)
    if shown:
        ax.legend(fontsize=8, loc="upper left")
    zeta = np.asarray(result.damping_ratio)
    below = np.nanmin(np.where(np.isfinite(freq), freq, np.inf), axis=0) <= fmax
    zeta = zeta[:, below] if below.any() else zeta
    for j in range(zeta.shape[1]):
        axd.plot(rpm, zeta[:, j], "-o", ms=2.5, lw=0.8, label=f"mode {j}" if j < 10 else None)
    axd.axhline(0.0, color="tab:red", lw=1.0)
    finite = zeta[np.isfinite(zeta)]
    if finite.size == 0 or np.abs(finite).max() < 1e-9:  # undamped: rounding noise only
        axd.set_ylim(-0.01, 0.01)
        axd.text(
            0.5,
            0.6,
            "undamped (|damping ratio| < 1e-9)",
            transform=axd.transAxes,
            ha="center",
            fontsize=9,
            color="0.3",
        )
    axd.set_xlim(rpm[0], rpm[-1])
    axd.set_xlabel("input speed [rpm]")
    axd.set_ylabel("damping ratio [-]")
    axd.grid(alpha=0.3)
    if zeta.shape[1]:
        axd.legend(fontsize=7, ncol=5, loc="best")
    return save(fig, path)


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
    """Undamped critical-speed map as a PNG: critical speeds [rpm] against bearing stiffness
    [N/m], log-log, one line per critical speed; each bearing's own stiffness dashed.

    >>> import numpy as np, tempfile, pathlib
    >>> from rheolin.stability.critical_map import CriticalSpeedMap
    >>> k = np.logspace(5, 9, 9)
    >>> r = CriticalSpeedMap(k, np.column_stack([np.sqrt(k / 20), 300 + 0 * k]), ["b"], {"b": 1e7})
    >>> plot_critical_map(r, pathlib.Path(tempfile.mkdtemp()) / "m.png").stat().st_size > 1000
    True
    """
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
            ax.annotate(f"{name}: {value:.3g} N/m", (value, 0.02),
                        xycoords=("data", "axes fraction"), rotation=90, fontsize=7,
                        ha="right", va="bottom", color="0.3")  # fmt: skip
    ax.set_xlabel("bearing stiffness [N/m] (isotropic, every bearing varied)")
    ax.set_ylabel("undamped critical speed [rpm]")
    ax.set_title("undamped critical-speed map (forward synchronous whirl)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    return save(fig, path)
