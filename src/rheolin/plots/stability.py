"""Stability map plot: largest Floquet real part against speed, unstable ranges shaded."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ._common import hatch_undecided, new_figure, save

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
    red and labelled with their bounds (and uncertainties) and mechanism; speeds whose
    verdict the truncation could still flip are marked with crosses and hatched (from
    halfway to the previous sample to halfway to the next): neither stable nor unstable.

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
    undecided = _undecided(map, len(rpm))
    bad = ~np.asarray(map.stable, bool) & ~undecided
    good = ~bad & ~undecided
    ax.plot(rpm[good], mr[good], "o", ms=3, color="tab:blue")
    if bad.any():  # a legend entry only for what is drawn
        ax.plot(rpm[bad], mr[bad], "o", ms=4, color="tab:red", label="unstable")
    if undecided.any():
        ax.plot(rpm[undecided], mr[undecided], "x", ms=7, color="k", label="verdict undecided")
        hatch_undecided(ax, rpm, undecided)
    ax.axhline(0.0, color="k", lw=0.8)
    for r in map.ranges:
        lo, hi = r.lower * RPM, r.upper * RPM
        ax.axvspan(lo, hi, color="tab:red", alpha=0.15, lw=0)
        open_lo = "<" if r.lower_open else ""
        open_hi = ">" if r.upper_open else ""
        ax.annotate(
            f"{open_lo}{_bound(lo, getattr(r, 'lower_uncertainty', np.nan) * RPM)} to "
            f"{_bound(hi, getattr(r, 'upper_uncertainty', np.nan) * RPM)}{open_hi} rpm\n"
            f"{_wrap(r.label)}",
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
    if undecided.any():
        status += f", {int(undecided.sum())} speed(s) undecided"
    ax.set_title(f"Floquet stability map: {status}")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="best")
    return save(fig, path)


def _undecided(map: Any, n: int) -> np.ndarray:
    """Per speed: the verdict is undecided (from the map's ``undecided`` or ``decided``)."""
    if hasattr(map, "undecided"):
        flags = np.asarray(map.undecided, bool)
        if flags.size == n:
            return flags
    decided = np.asarray(getattr(map, "decided", np.zeros(0, bool)), bool)
    return ~decided if decided.size == n else np.zeros(n, bool)


def _bound(x: float, unc: float) -> str:
    """``3439.46 +- 0.01`` (to the uncertainty's first digit), or ``3439.46`` without one."""
    if not np.isfinite(unc) or unc <= 0:
        return f"{x:.6g}"
    digits = max(0, min(6, -int(np.floor(np.log10(unc)))))
    return f"{x:.{digits}f} ± {unc:.1g}"
