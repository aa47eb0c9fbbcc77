"""Plots over speed: response vs speed per body and a waterfall, unstable ranges shaded."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.colors import LogNorm
from matplotlib.figure import Figure

from ._common import new_figure, save, shown_harmonics
from .layout import drop_overlapping

__all__ = ["sweep_figure", "sweep_plot"]


def sweep_plot(
    ds: xr.Dataset,
    path: str | Path,
    unstable_ranges_rpm: Sequence[tuple[float, float]] = (),
) -> Path:
    """Top: largest oscillating radial response per body vs speed (sum over harmonics, an
    upper bound of the peak); bottom: waterfall (speed vs frequency, colour = amplitude at the
    most responsive node) with shaft and mesh orders. Unstable speeds are shaded red:
    per-speed ``stable == 0`` and the given ``unstable_ranges_rpm``; unchecked speeds are grey
    ticks at the bottom (:func:`sweep_figure`)."""
    return save(sweep_figure(ds, unstable_ranges_rpm), path)


def sweep_figure(ds: xr.Dataset, unstable_ranges_rpm: Sequence[tuple[float, float]] = ()) -> Figure:
    """The figure of :func:`sweep_plot`."""
    fig, axes = new_figure(2, 1, (9, 9.5))
    ax, wf = axes[0, 0], axes[1, 0]
    rpm = ds["speed_rpm"].values
    osc = ds["harmonic"] > 0
    resp = ds["response"].where(osc, 0.0)
    for i, body in enumerate(dict.fromkeys(ds["body"].values.tolist())):
        per_node = resp.where(ds["body"] == body, drop=True).sum("harmonic")
        ax.semilogy(rpm, per_node.max("node") * 1e6, "o-", ms=3, color=f"C{i}", label=body)
    ax.set_ylabel("radial dynamic response [µm]")
    ax.set_xlabel("input speed [rpm]")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    step = float(np.median(np.diff(rpm))) if rpm.size > 1 else 1.0
    shaded = False
    for r, s in zip(rpm, ds["stable"].values, strict=True):
        if s == 0:
            for a in (ax, wf):
                a.axvspan(
                    r - step / 2, r + step / 2, color="tab:red", alpha=0.2, lw=0
                ) if a is ax else a.axhspan(
                    r - step / 2, r + step / 2, color="tab:red", alpha=0.2, lw=0
                )
            shaded = True
    for lo, hi in unstable_ranges_rpm:
        ax.axvspan(lo, hi, color="tab:red", alpha=0.2, lw=0)
        wf.axhspan(lo, hi, color="tab:red", alpha=0.2, lw=0)
        shaded = True
    unchecked = rpm[ds["stable"].values < 0]
    if unchecked.size:
        ax.plot(
            unchecked,
            np.full(unchecked.size, 0.02),
            "|",
            color="gray",
            transform=ax.get_xaxis_transform(),
            label="stability not checked",
        )
    note = "red: unstable" if shaded else "no unstable speed found"
    if unchecked.size == rpm.size:
        note = "stability not checked at these speeds"
    ax.set_title(f"response vs speed ({note})", fontsize=10)
    ax.legend(fontsize=8)
    node = str(resp.sum("harmonic").max("speed").idxmax("node").values)
    amp = resp.sel(node=node).values * 1e6  # (speed, harmonic); NaN where a point failed
    freq = ds["frequency"].values
    top = float(np.nanmax(amp))
    ok = np.zeros(amp.shape, bool)
    for i in range(amp.shape[0]):  # the harmonics each speed's spectrum shows
        ok[i] = shown_harmonics(amp[i], top)
    sc = wf.scatter(
        freq[ok],
        np.broadcast_to(rpm[:, None], amp.shape)[ok],
        c=amp[ok],
        s=10 + 50 * (amp[ok] / top) ** 0.5,
        cmap="viridis",
        norm=LogNorm(amp[ok].min(), top),
        zorder=3,
    )
    fig.colorbar(sc, ax=wf, label=f"radial amplitude at {node} [µm]")
    orders = json.loads(ds.attrs.get("marker_orders_json", "{}"))
    fmax = float(freq[ok].max()) * 1.08 if ok.any() else float(freq.max())
    texts = []
    for label, order in sorted(orders.items(), key=lambda kv: ("mesh" not in kv[0], -kv[1])):
        color = "tab:red" if "mesh" in label else "0.4"
        wf.plot(order * rpm / 60, rpm, "--", lw=0.8, color=color, zorder=2)
        x_end = order * rpm[-1] / 60
        if x_end <= fmax:
            texts.append(
                wf.annotate(
                    label,
                    (x_end, rpm[-1]),
                    xytext=(3, -2),
                    textcoords="offset points",
                    fontsize=7,
                    color=color,
                    va="top",
                    ha="left",
                )
            )
    wf.set_xlim(0, fmax)
    wf.set_ylim(rpm[0] - 0.5 * step, rpm[-1] + 0.5 * step)
    wf.set_xlabel("frequency [Hz]")
    wf.set_ylabel("input speed [rpm]")
    wf.set_title(
        "waterfall: harmonics within 60 dB (dashed: shaft speeds, mesh frequencies)", fontsize=10
    )
    wf.grid(alpha=0.3)
    drop_overlapping(texts, keep=[wf.title])
    return fig
