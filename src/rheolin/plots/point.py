"""Plots of one operating point from its results Dataset (see ``rheolin.results``)."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr

from ..results.dataset import complex_values
from ._common import mark_frequencies, new_figure, save

__all__ = [
    "default_nodes",
    "plot_bearing_spectra",
    "plot_convergence",
    "plot_orbits",
    "plot_spectrum",
    "point_plots",
]


def _radial(ds: xr.Dataset) -> xr.DataArray:
    q = complex_values(ds["displacement"])
    r = np.hypot(np.abs(q.sel(component="ux")), np.abs(q.sel(component="uy")))
    return r * xr.where(q["harmonic"] > 0, 2.0, 1.0)


def default_nodes(ds: xr.Dataset) -> list[str]:
    """Per body, the node with the largest oscillating radial response."""
    dyn = _radial(ds).where(ds["harmonic"] > 0, 0.0).sum("harmonic")
    out = []
    for body in dict.fromkeys(ds["body"].values.tolist()):
        out.append(str(dyn.where(ds["body"] == body, drop=True).idxmax("node").values))
    return out


def plot_orbits(ds: xr.Dataset, path: str | Path, nodes: Sequence[str] | None = None) -> Path:
    """Orbits ``(ux, uy)`` [um] over one revolution of each node's shaft."""
    nodes = list(nodes or default_nodes(ds))
    fig, axes = new_figure(1, len(nodes), (4.2 * len(nodes), 4.4))
    q = complex_values(ds["displacement"]).sel(component=["ux", "uy"])
    n = ds["harmonic"].values.astype(float)
    w1 = float(ds.attrs["base_frequency"])
    markers = json.loads(ds.attrs.get("markers_json", "{}"))
    for ax, node in zip(axes[0], nodes, strict=True):
        body = str(ds["body"].sel(node=node).values)
        f_rev = markers.get(f"{body} 1x", w1 / (2 * math.pi))
        period = 1.0 / f_rev
        fmax = float(ds["frequency"].max())
        samples = int(min(max(2000, 24 * fmax * period), 30000))
        t = np.linspace(0.0, period, samples)
        coef = q.sel(node=node).values * np.where(n > 0, 2.0, 1.0)[:, None]  # (harmonic, 2)
        big = np.abs(coef).max(axis=1) >= 1e-4 * np.abs(coef).max()  # visible harmonics only
        xy = (np.exp(1j * w1 * np.outer(t, n[big])) @ coef[big]).real * 1e6
        ax.plot(xy[:, 0], xy[:, 1], lw=0.6)
        ax.plot(xy[0, 0], xy[0, 1], "o", ms=4, color="tab:green", label="t = 0")
        mean = coef[n == 0].real[0] * 1e6 if np.any(n == 0) else np.zeros(2)
        ax.plot(*mean, "+", ms=10, color="k", label="static position")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("ux [µm]")
        ax.set_ylabel("uy [µm]")
        ax.set_title(f"{node}: one {body} revolution", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    fig.suptitle(_title(ds, "orbits"))
    return save(fig, path)


def plot_spectrum(ds: xr.Dataset, path: str | Path, nodes: Sequence[str] | None = None) -> Path:
    """Radial amplitude ``2|q_n|`` vs frequency at the nodes; shaft and mesh orders marked."""
    nodes = list(nodes or default_nodes(ds))
    fig, axes = new_figure(1, 1, (9, 5))
    ax = axes[0, 0]
    r = _radial(ds)
    f = ds["frequency"].values
    osc = ds["harmonic"].values > 0
    for i, node in enumerate(nodes):
        amp = r.sel(node=node).values[osc] * 1e6
        ok = amp > 0
        ax.vlines(f[osc][ok], 1e-12, amp[ok], color=f"C{i}", lw=0.8, alpha=0.6)
        ax.plot(f[osc][ok], amp[ok], "o", ms=3, color=f"C{i}", label=node)
    ax.set_yscale("log")
    top = float(max(r.sel(node=nodes).values[osc].max() * 1e6, 1e-9))
    ax.set_ylim(top * 1e-6, top * 3)
    ax.set_xlim(0, float(f.max()) * 1.02)
    mark_frequencies(ax, ds, float(f.max()))
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("radial amplitude [µm]")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title(_title(ds, "response spectrum"), fontsize=10)
    return save(fig, path)


def plot_bearing_spectra(ds: xr.Dataset, path: str | Path) -> Path:
    """Radial force amplitude per bearing vs frequency (one panel per bearing)."""
    names = [str(b) for b in ds["bearing"].values]
    cols = 2 if len(names) > 1 else 1
    rows = math.ceil(len(names) / cols)
    fig, axes = new_figure(rows, cols, (10, 2.4 * rows + 0.8))
    F = complex_values(ds["bearing_force"])
    Fr: xr.DataArray = np.hypot(
        np.abs(F.sel(force_component="Fx")), np.abs(F.sel(force_component="Fy"))
    )  # type: ignore[assignment]
    Mz: xr.DataArray = np.abs(F.sel(force_component="Mz"))  # type: ignore[assignment]
    f = ds["frequency"].values
    osc = ds["harmonic"].values > 0
    for k, ax in enumerate(axes.ravel()):
        if k >= len(names):
            ax.set_visible(False)
            continue
        b = names[k]
        radial = Fr.sel(bearing=b).values[osc] * 2
        moment = Mz.sel(bearing=b).values[osc] * 2
        amp, unit = (radial, "N") if radial.max(initial=0) > 0 else (moment, "N m")
        ok = amp > 0
        ax.vlines(f[osc][ok], 1e-15, amp[ok], lw=0.8, color="tab:blue", alpha=0.6)
        ax.plot(f[osc][ok], amp[ok], "o", ms=2.5, color="tab:blue")
        ax.set_yscale("log")
        if ok.any():
            ax.set_ylim(amp[ok].max() * 1e-5, amp[ok].max() * 3)
        mark_frequencies(ax, ds, float(f.max()))
        ax.set_title(f"{b} ({'radial force' if unit == 'N' else 'torsional moment'})", fontsize=9)
        ax.set_ylabel(f"amplitude [{unit}]")
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("frequency [Hz]")
    fig.suptitle(_title(ds, "bearing force spectra"), fontsize=10)
    return save(fig, path)


def plot_convergence(ds: xr.Dataset, path: str | Path) -> Path:
    """Relative residual per iteration."""
    fig, axes = new_figure(1, 1, (6, 4))
    ax = axes[0, 0]
    hist = ds["residual_history"].values
    if hist.size:
        ax.semilogy(np.arange(1, hist.size + 1), hist, "o-", ms=4)
    ax.axhline(
        float(ds.attrs["residual"]),
        color="tab:green",
        ls="--",
        lw=0.8,
        label=f"final residual {float(ds.attrs['residual']):.2e}",
    )
    ax.set_xlabel("iteration")
    ax.set_ylabel("relative residual ||f - A q|| / ||f||")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    ax.set_title(
        f"convergence: {ds.attrs['method']}, {int(ds.attrs['iterations'])} iterations", fontsize=10
    )
    return save(fig, path)


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
