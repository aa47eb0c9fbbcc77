"""``rheolin sweep --refine-peaks``: the speeds to add where a resonance peak of the run-up is
sampled too coarsely for its amplification factor (read back from ``sweep.json``)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..results.api684 import MIN_BAND_SAMPLES, Peak, refinement_speeds

__all__ = ["coarse_note", "coarse_peaks", "refined_speeds"]

RAD = math.pi / 30  # rpm -> rad/s


def coarse_peaks(out_dir: Path) -> list[dict[str, Any]]:
    """The resonances of ``out_dir/sweep.json`` with fewer than
    :data:`~rheolin.results.api684.MIN_BAND_SAMPLES` samples in their half-power band."""
    path = Path(out_dir) / "sweep.json"
    if not path.is_file():
        return []
    table = json.loads(path.read_text(encoding="utf-8"))
    return [r for r in table.get("resonances", []) if r.get("resolved") is False]


def coarse_note(peaks: list[dict[str, Any]]) -> str:
    """The warning for coarsely sampled peaks (empty when there are none)."""
    if not peaks:
        return ""
    where = ", ".join(
        f"{p['body']} {p['speed_rpm']:.0f} rpm ({p['samples_in_band']})" for p in peaks
    )
    return (
        f"{len(peaks)} resonance peak(s) have fewer than {MIN_BAND_SAMPLES} speeds in their "
        f"half-power band: {where}; their amplification factor is interpolated across a "
        "coarse step (add speeds there: --refine-peaks)"
    )


def refined_speeds(out_dir: Path, speeds: np.ndarray) -> np.ndarray | None:
    """``speeds`` [rad/s] with the speeds that resolve every coarse peak of the sweep in
    ``out_dir`` added (:func:`~rheolin.results.api684.refinement_speeds`), or None when every
    peak is resolved or no speed can be added."""
    extra = []
    for r in coarse_peaks(out_dir):
        band = r.get("half_power_rpm")
        peak = Peak(
            speed=float(r["speed_rpm"]) * RAD,
            amplitude=float(r["amplitude_m"]),
            lower=None if band is None else float(band[0]) * RAD,
            upper=None if band is None else float(band[1]) * RAD,
            amplification_factor=r.get("amplification_factor"),
            samples=int(r.get("samples_in_band", 0)),
        )
        extra.append(refinement_speeds(peak, speeds))
    added = np.concatenate(extra) if extra else np.zeros(0)
    if added.size == 0:
        return None
    return np.unique(np.concatenate([np.asarray(speeds, dtype=float), added]))
