"""Shared helpers: a Figure without pyplot, atomic saving, frequency markers."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..io.atomic import atomic_write

__all__ = [
    "FORMATS",
    "length_unit",
    "mark_frequencies",
    "new_figure",
    "save",
    "shown_harmonics",
]

#: Formats :func:`save` writes, by the file's suffix (anything else: PNG).
FORMATS = ("png", "svg", "pdf")

#: Spectra show the harmonics within this factor of their largest (60 dB) ...
DYNAMIC_RANGE = 1e-3
#: ... and at most this many per curve, the largest.
MOST_HARMONICS = 60


def new_figure(rows: int = 1, cols: int = 1, size: tuple[float, float] = (8, 5)) -> Any:
    """A Figure (Agg canvas, no global pyplot state) and its axes."""
    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(rows, cols, squeeze=False)
    return fig, axes


def save(fig: Figure, path: str | Path) -> Path:
    """Save atomically: PNG, or SVG/PDF by the file's suffix."""
    suffix = Path(path).suffix.lower().lstrip(".")
    with atomic_write(path) as tmp:
        fig.savefig(tmp, format=suffix if suffix in FORMATS else "png", dpi=110)
    return Path(path)


def length_unit(largest_m: float) -> tuple[str, float]:
    """The unit a length of ``largest_m`` metres reads best in, and metres' factor to it.

    >>> length_unit(3e-6), length_unit(4e-10), length_unit(0.02)
    (('µm', 1000000.0), ('nm', 1000000000.0), ('mm', 1000.0))
    """
    for unit, scale in (("mm", 1e3), ("µm", 1e6)):
        if abs(largest_m) * scale >= 0.1:
            return unit, scale
    return "nm", 1e9


def shown_harmonics(amplitude: np.ndarray, top: float | None = None) -> np.ndarray:
    """Mask of the entries of ``amplitude`` a spectrum draws: within :data:`DYNAMIC_RANGE`
    of ``top`` (default: their largest), at most :data:`MOST_HARMONICS` of the largest.

    >>> shown_harmonics(np.array([1.0, 1e-4, 0.5, 0.0])).tolist()
    [True, False, True, False]
    """
    a = np.nan_to_num(np.asarray(amplitude, dtype=float))
    top = float(a.max(initial=0.0)) if top is None else float(top)
    keep = a > DYNAMIC_RANGE * top
    if keep.sum() > MOST_HARMONICS:
        keep &= a >= np.sort(a[keep])[-MOST_HARMONICS]
    return np.asarray(keep & (a > 0))


def mark_frequencies(
    ax: Any, ds: xr.Dataset, lo: float, hi: float, labels: bool = True
) -> list[Any]:
    """Dashed vertical lines at the shaft speeds and mesh frequencies [Hz] within
    ``[lo, hi]``, labelled at the top of the panel when ``labels``; returns the labels
    (meshes first: the caller hides those that overlap, :func:`~.layout.drop_overlapping`)."""
    markers = json.loads(ds.attrs.get("markers_json", "{}"))
    texts = []
    for label, f in sorted(markers.items(), key=lambda kv: ("mesh" not in kv[0], kv[1])):
        if not lo <= f <= hi or f <= 0:
            continue
        color = "tab:red" if "mesh" in label else "0.35"
        ax.axvline(f, color=color, lw=0.8, ls="--", alpha=0.7)
        if labels:
            texts.append(
                ax.annotate(
                    label,
                    (f, 1.0),
                    xycoords=("data", "axes fraction"),
                    rotation=90,
                    va="top",
                    ha="right",
                    fontsize=7,
                    color=color,
                    xytext=(-2, -3),
                    textcoords="offset points",
                )
            )
    return texts


def hatch_undecided(axes: Any, rpm: np.ndarray, undecided: np.ndarray) -> None:
    """Hatch each undecided speed on ``axes`` (an Axes or several), from halfway to the
    previous sample to halfway to the next: neither stable nor unstable."""
    rpm = np.asarray(rpm, dtype=float)
    edges = np.concatenate([[rpm[0]], 0.5 * (rpm[1:] + rpm[:-1]), [rpm[-1]]])
    for i in np.flatnonzero(np.asarray(undecided, dtype=bool)):
        for ax in np.atleast_1d(axes):
            ax.axvspan(edges[i], edges[i + 1], fc="none", ec="0.35", hatch="///", lw=0)
