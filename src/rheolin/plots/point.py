"""Plots of one operating point from its results Dataset (see ``rheolin.results``).

Each plot has a ``*_figure`` that returns the Figure (what the tests and the gallery check,
:mod:`rheolin.plots.layout`) and a ``plot_*`` that writes it.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator, NullFormatter

from ..results.dataset import complex_values
from ._common import length_unit, mark_frequencies, new_figure, save, shown_harmonics
from .layout import drop_overlapping

__all__ = [
    "bearing_amplitudes",
    "bearing_spectra_figure",
    "convergence_figure",
    "default_nodes",
    "orbits_figure",
    "plot_bearing_spectra",
    "plot_convergence",
    "plot_orbits",
    "plot_spectrum",
    "point_plots",
    "radial_amplitude",
    "spectrum_figure",
]


def radial_amplitude(ds: xr.Dataset) -> xr.DataArray:
    """Radial amplitude ``hypot(|ux|, |uy|)`` per node and harmonic, single-sided (``2 |x_n|``
    for ``n > 0``) [m]."""
    q = complex_values(ds["displacement"])
    r = np.hypot(np.abs(q.sel(component="ux")), np.abs(q.sel(component="uy")))
    return r * xr.where(q["harmonic"] > 0, 2.0, 1.0)


def default_nodes(ds: xr.Dataset) -> list[str]:
    """Per body, the node with the largest oscillating radial response."""
    dyn = radial_amplitude(ds).where(ds["harmonic"] > 0, 0.0).sum("harmonic")
    out = []
    for body in dict.fromkeys(ds["body"].values.tolist()):
        out.append(str(dyn.where(ds["body"] == body, drop=True).idxmax("node").values))
    return out


def orbits_figure(ds: xr.Dataset, nodes: Sequence[str] | None = None) -> Figure:
    """Orbits over one revolution of each node's shaft, drawn about the node's static
    position (given in the panel's title: a large static deflection would make a small
    orbit a dot)."""
    nodes = list(nodes or default_nodes(ds))
    fig, axes = new_figure(1, len(nodes), (4.2 * len(nodes), 4.6))
    q = complex_values(ds["displacement"]).sel(component=["ux", "uy"])
    n = ds["harmonic"].values.astype(float)
    w1 = float(ds.attrs["base_frequency"])
    markers = json.loads(ds.attrs.get("markers_json", "{}"))
    fmax = float(ds["frequency"].max())
    for ax, node in zip(axes[0], nodes, strict=True):
        body = str(ds["body"].sel(node=node).values)
        period = 1.0 / markers.get(f"{body} 1x", w1 / (2 * math.pi))
        samples = int(min(max(2000, 24 * fmax * period), 30000))
        t = np.linspace(0.0, period, samples)
        coef = q.sel(node=node).values * np.where(n > 0, 2.0, 1.0)[:, None]  # (harmonic, 2)
        osc = (n > 0) & (np.abs(coef).max(axis=1) >= 1e-4 * np.abs(coef[n > 0]).max(initial=0.0))
        xy = (np.exp(1j * w1 * np.outer(t, n[osc])) @ coef[osc]).real
        unit, scale = length_unit(float(np.abs(xy).max(initial=0.0)))
        xy = xy * scale
        static = coef[n == 0].real[0] * 1e6 if np.any(n == 0) else np.zeros(2)
        ax.plot(xy[:, 0], xy[:, 1], lw=0.7, color="tab:blue", label="orbit")
        ax.plot(xy[0, 0], xy[0, 1], "o", ms=5, color="tab:green", label="t = 0")
        ax.plot(0.0, 0.0, "+", ms=12, mew=1.5, color="k", label="static position")
        ax.set_aspect("equal", adjustable="datalim")
        ax.xaxis.set_major_locator(MaxNLocator(5))
        ax.yaxis.set_major_locator(MaxNLocator(5))
        ax.set_xlabel(f"ux - static [{unit}]")
        ax.set_ylabel(f"uy - static [{unit}]")
        ax.set_title(
            f"{node}: one {body} revolution\nstatic position ({static[0]:.3g}, {static[1]:.3g}) µm",
            fontsize=9,
        )
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7, loc="upper left")
    fig.suptitle(_title(ds, "orbits (dynamic part)"), fontsize=11)
    return fig


def plot_orbits(ds: xr.Dataset, path: str | Path, nodes: Sequence[str] | None = None) -> Path:
    """Orbits ``(ux, uy)`` [µm] over one revolution of each node's shaft (see
    :func:`orbits_figure`)."""
    return save(orbits_figure(ds, nodes), path)


def _stems(ax: Any, f: np.ndarray, amp: np.ndarray, color: str, label: str | None) -> None:
    ax.vlines(f, 1e-30, amp, color=color, lw=0.9, alpha=0.7)
    ax.plot(f, amp, "o", ms=3.5, color=color, label=label)


def _frequency_axis(ax: Any, shown: np.ndarray) -> tuple[float, float]:
    """A log frequency axis around the frequencies drawn, linear from 0 when they span
    less than a decade."""
    lo = float(shown.min()) / 1.6 if shown.size else 1.0
    hi = float(shown.max()) * 1.6 if shown.size else 10.0
    if hi / lo < 10.0:
        lo, hi = 0.0, float(shown.max()) * 1.25 if shown.size else 10.0
        ax.set_xlim(lo, hi)
        return lo, hi
    ax.set_xscale("log")
    ax.set_xlim(lo, hi)
    ax.xaxis.set_minor_formatter(NullFormatter())
    return lo, hi


def spectrum_figure(ds: xr.Dataset, nodes: Sequence[str] | None = None) -> Figure:
    """Radial amplitude ``2|q_n|`` against frequency (log-log) at the nodes, the harmonics
    within 60 dB of the largest (at most 60 per node); shaft speeds and mesh frequencies
    marked."""
    nodes = list(nodes or default_nodes(ds))
    fig, axes = new_figure(1, 1, (9, 5.2))
    ax = axes[0, 0]
    r = radial_amplitude(ds)
    f = ds["frequency"].values
    osc = ds["harmonic"].values > 0
    top = float(max(r.sel(node=nodes).values[osc].max(initial=0.0) * 1e6, 1e-12))
    drawn, total = [], 0
    for i, node in enumerate(nodes):
        amp = r.sel(node=node).values[osc] * 1e6
        keep = shown_harmonics(amp, top)
        total += int((amp > 0).sum())
        _stems(ax, f[osc][keep], amp[keep], f"C{i}", node)
        drawn.append(f[osc][keep])
    shown = np.concatenate(drawn)
    ax.set_yscale("log")
    ax.set_ylim(top * 5e-4, top * 3)
    lo, hi = _frequency_axis(ax, shown)
    texts = mark_frequencies(ax, ds, lo, hi)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("radial amplitude 2|q_n| [µm]")
    ax.grid(alpha=0.3, which="both")
    legend = ax.legend(fontsize=8, loc="lower left", title="node", title_fontsize=8)
    ax.set_title(
        _title(ds, "response spectrum")
        + f"\n{shown.size} largest harmonics within 60 dB shown (of {total})",
        fontsize=10,
    )
    drop_overlapping(texts, keep=[legend, ax.title])
    return fig


def plot_spectrum(ds: xr.Dataset, path: str | Path, nodes: Sequence[str] | None = None) -> Path:
    """Radial amplitude spectrum at the nodes (see :func:`spectrum_figure`)."""
    return save(spectrum_figure(ds, nodes), path)


#: What a bearing panel shows, by the joint's components: label, force components, unit.
_QUANTITIES = (
    ("radial force", ("Fx", "Fy"), "N"),
    ("axial force", ("Fz",), "N"),
    ("torsional moment", ("Mz",), "N m"),
    ("tilting moment", ("Mx", "My"), "N m"),
)


def bearing_amplitudes(ds: xr.Dataset, b: str) -> list[tuple[str, str, np.ndarray]]:
    """The oscillating amplitudes of bearing ``b`` that are not zero: ``(quantity, unit,
    amplitude per oscillating harmonic)``, radial first."""
    F = complex_values(ds["bearing_force"].sel(bearing=b))
    osc = ds["harmonic"].values > 0
    out = []
    for name, comps, unit in _QUANTITIES:
        amp = np.sqrt(sum(np.abs(F.sel(force_component=c).values) ** 2 for c in comps))[osc] * 2
        if amp.max(initial=0.0) > 0:
            out.append((name, unit, amp))
    return out


def bearing_spectra_figure(ds: xr.Dataset) -> Figure:
    """One panel per bearing with a dynamic load: the amplitude of its largest kind of load
    (radial force, else axial force, torsional or tilting moment, by what the joint carries)
    against frequency; bearings without a dynamic load are named in the title."""
    names = [str(b) for b in ds["bearing"].values]
    found = [(b, bearing_amplitudes(ds, b)) for b in names]
    quiet = [b for b, q in found if not q]
    panels = [(b, q[0]) for b, q in found if q]
    cols = 2 if len(panels) > 1 else 1
    rows = max(math.ceil(len(panels) / cols), 1)
    fig, axes = new_figure(rows, cols, (10, 2.6 * rows + 1.0))
    f = ds["frequency"].values[ds["harmonic"].values > 0]
    shown_all = [f[shown_harmonics(q[2])] for _, q in panels]
    span = np.concatenate(shown_all) if shown_all else np.zeros(0)
    texts: list[Any] = []
    first = True
    for k, ax in enumerate(axes.ravel()):
        if k >= len(panels):
            ax.set_visible(False)
            continue
        b, (quantity, unit, amp) = panels[k]
        keep = shown_harmonics(amp)
        _stems(ax, f[keep], amp[keep], "tab:blue", None)
        ax.set_yscale("log")
        ax.set_ylim(amp.max() * 5e-4, amp.max() * 3)
        lo, hi = _frequency_axis(ax, span)
        texts += mark_frequencies(ax, ds, lo, hi, labels=first)
        first = False
        ax.set_title(f"{b}: {quantity}", fontsize=9)
        ax.set_ylabel(f"amplitude [{unit}]")
        ax.grid(alpha=0.3, which="both")
    for ax in axes[-1]:
        ax.set_xlabel("frequency [Hz]")
    title = _title(ds, "bearing load spectra (dashed: shaft speeds, mesh frequencies)")
    if quiet:
        title += "\nno dynamic load: " + ", ".join(quiet)
    fig.suptitle(title, fontsize=10)
    drop_overlapping(texts, keep=[a.title for a in fig.axes])
    return fig


def plot_bearing_spectra(ds: xr.Dataset, path: str | Path) -> Path:
    """Load spectra per bearing (see :func:`bearing_spectra_figure`)."""
    return save(bearing_spectra_figure(ds), path)


def convergence_figure(ds: xr.Dataset) -> Figure:
    """The iterative solver's own residual estimate per iteration, the tolerance it stops
    at, and the backward error recomputed from the final answer."""
    fig, axes = new_figure(1, 1, (6.5, 4.2))
    ax = axes[0, 0]
    hist = ds["residual_history"].values
    final = float(ds.attrs["residual"])
    rtol = float(ds.attrs.get("rtol", float("nan")))
    last = max(hist.size, 1)
    if hist.size:
        ax.semilogy(np.arange(1, hist.size + 1), hist, "o-", ms=4, label="solver's estimate")
    if math.isfinite(rtol):
        ax.axhline(rtol, color="0.4", ls=":", lw=1.0, label=f"tolerance (--rtol) {rtol:.0e}")
    if math.isfinite(final) and final > 0:
        ax.semilogy(
            [last],
            [final],
            "*",
            ms=12,
            color="tab:green",
            label=f"backward error, recomputed: {final:.2e}",
        )
    else:
        ax.set_yscale("log")
    values = [v for v in [*hist, final, rtol] if math.isfinite(v) and v > 0]
    if values:  # whole decades: no tick label cut at the panel's edge
        ax.set_ylim(
            10 ** math.floor(math.log10(min(values))), 10 ** math.ceil(math.log10(max(values)))
        )
    ax.set_xlabel("iteration")
    ax.set_ylabel("backward error ||f - A q|| / (||A|| ||q|| + ||f||)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="upper right")
    ax.set_title(
        f"convergence: {ds.attrs['method']}, {int(ds.attrs['iterations'])} iterations", fontsize=10
    )
    return fig


def plot_convergence(ds: xr.Dataset, path: str | Path) -> Path:
    """Residual per iteration (see :func:`convergence_figure`)."""
    return save(convergence_figure(ds), path)


def point_plots(ds: xr.Dataset, out: str | Path, nodes: Sequence[str] | None = None) -> list[Path]:
    """All plots of one operating point into directory ``out``; returns the paths."""
    d = Path(out)
    paths = [
        plot_orbits(ds, d / "orbits.png", nodes),
        plot_spectrum(ds, d / "spectrum.png", nodes),
        plot_convergence(ds, d / "convergence.png"),
    ]
    if "bearing_force" in ds:
        paths.append(plot_bearing_spectra(ds, d / "bearing_forces.png"))
    return paths


def _title(ds: xr.Dataset, what: str) -> str:
    return f"{what} at {float(ds.attrs['speed_rpm']):.0f} rpm ({ds.attrs.get('stability')})"
