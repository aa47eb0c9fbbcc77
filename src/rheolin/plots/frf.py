"""Bode plot of frequency response functions (magnitude and phase against frequency)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ._common import new_figure, save
from .layout import drop_overlapping

__all__ = ["bode_figure", "plot_bode"]

HZ = 1.0 / (2.0 * np.pi)

#: At most this many (output, input) pairs in one plot.
MAX_PAIRS = 6


def plot_bode(frf: Any, path: str | Path, pairs: list[tuple[str, str]] | None = None) -> Path:
    """Bode plot as a PNG (:func:`bode_figure`).

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib, rheolin as rl
    >>> from rheolin.results.frf import system_frequency_response
    >>> s = rl.PeriodicSystem(1.0, M={0: np.eye(1)}, D={0: 0.2 * np.eye(1)}, K={0: 4 * np.eye(1)})
    >>> frf = system_frequency_response(s, np.linspace(0.1, 5, 50), inputs=[0])
    >>> plot_bode(frf, pathlib.Path(tempfile.mkdtemp()) / "b.png").stat().st_size > 1000
    True
    """
    return save(bode_figure(frf, pairs), path)


def bode_figure(frf: Any, pairs: list[tuple[str, str]] | None = None) -> Figure:
    """``|H|`` (log scale) over phase [deg], against frequency [Hz].

    One line per (output, input) pair (default: the driving points, output = input, else the
    first pairs; at most :data:`MAX_PAIRS`), in its unit (m/N, rad/(N m), ...). Each pair's
    resonance peaks are marked with their frequency and half-power amplification factor. For
    a time-periodic system the largest sideband of each pair (the response at ``w + h w1``,
    ``h != 0``) is drawn thin and dashed in the same colour: how much of the response leaves
    the excitation frequency."""
    from ..results.api684 import amplification_factors
    from ..results.frf import receptance_unit

    outs, ins = list(frf.outputs), list(frf.inputs)
    if pairs is None:
        pairs = [(o, o) for o in outs if o in ins] or [(o, i) for o in outs for i in ins]
    pairs = pairs[:MAX_PAIRS]
    f = np.asarray(frf.frequencies) * HZ
    H = frf.receptance
    side = frf.sidebands != 0
    fig, axes = new_figure(2, 1, (9, 7.5))
    ax, axp = axes[0, 0], axes[1, 0]
    units = sorted({receptance_unit(o, i, frf.unbalance) for o, i in pairs})
    texts, sidebands = [], False
    for k, (o, i) in enumerate(pairs):
        color = f"C{k % 10}"
        h = H[:, outs.index(o), ins.index(i)]
        mag = np.abs(h)
        unit = receptance_unit(o, i, frf.unbalance)
        label = (o if o == i else f"{o} / {i}") + (f" [{unit}]" if len(units) > 1 else "")
        ax.semilogy(f, np.where(mag > 0, mag, np.nan), color=color, lw=1.4, label=label)
        axp.plot(f, np.degrees(np.angle(h)), color=color, lw=1.2)
        if side.any():
            sb = np.abs(frf.response[:, side, outs.index(o), ins.index(i)]).max(axis=1)
            if np.nanmax(sb, initial=0.0) > 0:
                ax.semilogy(f, np.where(sb > 0, sb, np.nan), color=color, lw=0.8, ls="--")
                sidebands = True
        finite = np.nan_to_num(mag)
        if f.size >= 3 and finite.max() > 0 and np.all(np.diff(f) > 0):
            for p in amplification_factors(f, finite):
                if p.amplitude < 0.05 * finite.max():
                    continue
                af = "" if p.amplification_factor is None else f", AF {p.amplification_factor:.3g}"
                ax.plot(p.speed, p.amplitude, "v", color=color, ms=7, mec="k", mew=0.5)
                texts.append(
                    ax.annotate(
                        f"{p.speed:.4g} Hz{af}",
                        (p.speed, p.amplitude),
                        xytext=(0, 7),
                        textcoords="offset points",
                        ha="center",
                        fontsize=7,
                        color=color,
                    )
                )
    handles, _ = ax.get_legend_handles_labels()
    if texts:
        handles.append(
            Line2D(
                [],
                [],
                marker="v",
                ls="",
                color="0.4",
                mec="k",
                mew=0.5,
                label="peak: frequency, half-power AF",
            )
        )
    if sidebands:
        handles.append(
            Line2D(
                [],
                [],
                ls="--",
                lw=0.8,
                color="0.3",
                label="largest sideband w + h w1 (same colour)",
            )
        )
    speed = frf.speed * 30 / np.pi if np.isfinite(frf.speed) else None
    title = "frequency response" + (f" at {speed:.0f} rpm" if speed is not None else "")
    ax.set_title(title)
    unit = units[0] if len(units) == 1 else "per unit input"
    ax.set_ylabel(f"|H| [{unit}]")
    ax.grid(True, which="both", alpha=0.3)
    legend = ax.legend(handles=handles, fontsize=8, loc="best")
    axp.set_ylabel("phase [deg]")
    axp.set_xlabel("excitation frequency [Hz]")
    axp.set_yticks([-180, -90, 0, 90, 180])
    axp.set_ylim(-185, 185)
    axp.grid(True, alpha=0.3)
    for a in (ax, axp):
        a.set_xlim(f.min(), f.max())
    low, high = ax.get_ylim()
    ax.set_ylim(low, high * 4)  # room for the peak labels
    drop_overlapping(texts, keep=[legend, ax.title])
    return fig
