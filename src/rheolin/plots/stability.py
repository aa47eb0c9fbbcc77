"""Stability map plot: largest Floquet real part against speed, unstable ranges shaded."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ._common import new_figure, save

__all__ = ["plot_stability"]


def _wrap(text: str, width: int = 38) -> str:
    import textwrap

    return "\n".join(textwrap.wrap(text, width)) or text


RPM = 60.0 / (2.0 * np.pi)


def plot_stability(map: Any, path: str | Path) -> Path:
    """Stability map as a PNG.

    Largest Floquet real part [1/s] against input speed [rpm] (symmetric-log axis when
    damped and growing values must both show, else linear up to zero), the per-speed
    decision tolerance as a grey band, unstable samples as red dots, unstable ranges shaded
    red and labelled with their bounds and mechanism; speeds whose verdict the truncation
    could still flip are marked with crosses.

    Parameters
    ----------
    map
        A :class:`~rheolin.stability.StabilityMap`.
    path
        PNG file to write.

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib
    >>> from rheolin.stability import StabilityMap, UnstableRange
    >>> W = np.linspace(1.0, 5.0, 5)
    >>> m = StabilityMap(W, np.array([-1, -0.5, 0.2, -0.5, -1.0]), np.full(5, 1e-9),
    ...                  np.array([1, 1, 0, 1, 1], bool), np.zeros(5, bool), np.ones(5, bool),
    ...                  np.ones(5), [UnstableRange(2.5, 3.5, False, False, 0.2, "x")])
    >>> plot_stability(m, pathlib.Path(tempfile.mkdtemp()) / "s.png").stat().st_size > 1000
    True
    """
    fig, axes = new_figure(1, 1, (9, 5.5))
    ax = axes[0, 0]
    rpm = np.asarray(map.speeds) * RPM
    mr = np.asarray(map.max_real, dtype=float)
    tol = np.asarray(map.tol, dtype=float)
    finite = np.isfinite(mr)
    scale = float(np.nanmax(np.abs(mr[finite]))) if finite.any() else 1.0
    linthresh = max(1e-3 * scale, float(np.nanmax(tol)) if tol.size else 0.0, 1e-12)
    growing = finite.any() and float(np.nanmax(mr[finite])) > -linthresh
    if growing:  # damped and growing values both: a symmetric-log axis shows both
        ax.set_yscale("symlog", linthresh=linthresh)
    else:  # all damped: a linear axis from the most damped value up to the boundary
        ax.set_ylim(-1.15 * scale, 0.15 * scale)
    visible = tol.size and float(np.nanmax(tol)) > 0.005 * scale  # else a hairline: no entry
    ax.fill_between(rpm, -tol, tol, color="0.8", lw=0,
                    label="decision tolerance" if visible else None)  # fmt: skip
    ax.plot(rpm, mr, "-", color="tab:blue", lw=1.2, label="largest Floquet real part")
    bad = ~np.asarray(map.stable, bool)
    ax.plot(rpm[~bad], mr[~bad], "o", ms=3, color="tab:blue")
    if bad.any():  # a legend entry only for what is drawn
        ax.plot(rpm[bad], mr[bad], "o", ms=4, color="tab:red", label="unstable")
    decided = getattr(map, "decided", np.zeros(0, bool))
    undecided = ~np.asarray(decided, bool) if len(decided) == len(rpm) else np.zeros(len(rpm), bool)
    if undecided.any():
        ax.plot(rpm[undecided], mr[undecided], "x", ms=7, color="k", label="verdict undecided")
    ax.axhline(0.0, color="k", lw=0.8)
    for r in map.ranges:
        lo, hi = r.lower * RPM, r.upper * RPM
        ax.axvspan(lo, hi, color="tab:red", alpha=0.15, lw=0)
        open_lo = "<" if r.lower_open else ""
        open_hi = ">" if r.upper_open else ""
        ax.annotate(
            f"{open_lo}{lo:.6g} to {hi:.6g}{open_hi} rpm\n{_wrap(r.label)}",
            (0.5 * (lo + hi), 0.45),
            xycoords=("data", "axes fraction"),
            ha="center",
            va="center",
            bbox={"boxstyle": "round", "fc": "white", "ec": "tab:red", "alpha": 0.85},
            fontsize=8,
            color="tab:red",
            xytext=(0, -4),
            textcoords="offset points",
        )
    ax.set_xlim(rpm[0], rpm[-1])
    ax.set_xlabel("input speed [rpm]")
    ax.set_ylabel("largest Floquet real part [1/s]")
    status = (
        "stable over the whole range" if not bad.any() else f"{len(map.ranges)} unstable range(s)"
    )
    ax.set_title(f"Floquet stability map: {status}")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="best")
    return save(fig, path)
