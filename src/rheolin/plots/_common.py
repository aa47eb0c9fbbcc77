"""Shared helpers: a Figure without pyplot, atomic PNG saving, frequency markers."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from ..io.atomic import atomic_write

__all__ = ["mark_frequencies", "new_figure", "save"]


def new_figure(rows: int = 1, cols: int = 1, size: tuple[float, float] = (8, 5)) -> Any:
    """A Figure (Agg canvas, no global pyplot state) and its axes."""
    fig = Figure(figsize=size, layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False)
    return fig, axes


def save(fig: Figure, path: str | Path) -> Path:
    """Save as PNG atomically."""
    with atomic_write(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    return Path(path)


def mark_frequencies(ax: Any, ds: xr.Dataset, fmax: float, scale: float = 1.0) -> None:
    """Dashed vertical lines at the shaft speeds and mesh frequencies below ``fmax``."""
    markers = json.loads(ds.attrs.get("markers_json", "{}"))
    last = -np.inf
    for label, f in sorted(markers.items(), key=lambda kv: kv[1]):
        if 0 < f * scale <= fmax:
            color = "tab:red" if "mesh" in label else "tab:gray"
            ax.axvline(f * scale, color=color, lw=0.8, ls="--", alpha=0.7)
            if f * scale - last < 0.025 * fmax:
                continue  # keep labels legible: skip one that would overlap its neighbour
            last = f * scale
            ax.annotate(
                label,
                (f * scale, 1.0),
                xycoords=("data", "axes fraction"),
                rotation=90,
                va="top",
                ha="right",
                fontsize=7,
                color=color,
                xytext=(-2, -2),
                textcoords="offset points",
            )
