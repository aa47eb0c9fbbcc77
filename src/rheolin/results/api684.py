"""Amplification factors and separation margins of an unbalance response (API 684 / API 617).

From a response amplitude sampled over speed (a run-up: ``rheolin sweep``), each resonance
peak gets

* its **amplification factor** by the half-power method, ``AF = N_c / (N_2 - N_1)``, with
  ``N_1 < N_c < N_2`` the speeds where the amplitude is ``peak / sqrt(2)`` (linear
  interpolation between samples; the peak itself refined by a parabola through its three
  samples);
* the **separation margin** it has from the operating range ``[N_min, N_max]`` and the one API
  617 (7th ed., 2.6.2.10; the method of API RP 684) requires: none when ``AF < 2.5`` (critically
  damped), else ``17 (1 - 1 / (AF - 1.5))`` % below ``N_min``, ``10 + 17 (1 - 1 / (AF - 1.5))``
  % above ``N_max``.

A peak whose half-power points lie outside the sampled range has no AF (``None``): extend the
sweep. The amplitude should be a magnitude (e.g. the major semi-axis of an orbit, or a bearing
force), sampled finely enough to resolve the peak: a peak with fewer than
:data:`MIN_BAND_SAMPLES` samples inside its half-power band is not ``resolved`` (its AF comes
from interpolating between samples too far apart), and :func:`refinement_speeds` gives the
speeds to add there (``rheolin sweep --refine-peaks``).

>>> import numpy as np
>>> w = np.linspace(50.0, 150.0, 2001)      # an SDOF rotor, zeta = 0.05, w_n = 100 rad/s
>>> x = w**2 / np.abs(1e4 - w**2 + 2j * 0.05 * 100 * w)
>>> (p,) = amplification_factors(w, x)
>>> round(p.speed, 1), round(p.amplification_factor, 2)
(100.3, 9.9)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "MIN_BAND_SAMPLES",
    "Peak",
    "amplification_factors",
    "refinement_speeds",
    "required_margin",
    "separation_margin",
]

#: Below this amplification factor a resonance is critically damped (no margin required).
CRITICALLY_DAMPED = 2.5
#: A peak is resolved with at least this many samples inside its half-power band (an SDOF
#: sampled so: its AF within 2.5 % of the closed form; bench figures in the commit message).
MIN_BAND_SAMPLES = 5


def required_margin(af: float | None, below: bool) -> float:
    """The separation margin [fraction] API 617 requires of a resonance with amplification
    factor ``af``, below the minimum operating speed (``below``) or above the maximum.

    >>> required_margin(2.0, True), round(required_margin(10.0, False), 4)
    (0.0, 0.25)
    """
    if af is None or af < CRITICALLY_DAMPED:
        return 0.0
    base = 0.17 * (1.0 - 1.0 / (af - 1.5))
    return base if below else 0.10 + base


@dataclass(frozen=True)
class Peak:
    """One resonance of a response over speed (speeds in the units given)."""

    speed: float
    amplitude: float
    lower: float | None
    upper: float | None
    amplification_factor: float | None
    #: Distance to the operating range as a fraction of the nearest operating limit
    #: (negative inside it); None without an operating range.
    margin: float | None = None
    #: What API 617 requires of this peak (0 when critically damped).
    required: float | None = None
    #: Samples strictly inside the half-power band ``(lower, upper)`` (0 without an AF).
    samples: int = 0

    @property
    def resolved(self) -> bool:
        """At least :data:`MIN_BAND_SAMPLES` samples inside the half-power band: the AF is
        not an interpolation across a coarse step."""
        return self.samples >= MIN_BAND_SAMPLES

    @property
    def acceptable(self) -> bool | None:
        """The margin meets the requirement (None without an operating range)."""
        if self.margin is None or self.required is None:
            return None
        return self.margin >= self.required


def _crossing(s: np.ndarray, a: np.ndarray, level: float, i: int, step: int) -> float | None:
    """Walk from sample ``i`` by ``step`` to where ``a`` drops below ``level``."""
    j = i
    while 0 <= j + step < a.size:
        k = j + step
        if a[k] <= level:
            return float(s[j] + (level - a[j]) * (s[k] - s[j]) / (a[k] - a[j]))
        j = k
    return None


def amplification_factors(
    speeds: np.ndarray,
    amplitude: np.ndarray,
    operating: tuple[float, float] | None = None,
    *,
    prominence: float = 0.1,
) -> list[Peak]:
    """The resonance peaks of ``amplitude(speeds)``, their half-power amplification factors
    and, with ``operating = (N_min, N_max)``, their separation margins and the API 617
    requirement.

    Peaks are the local maxima at least ``prominence`` (relative to the peak) above the lower
    of the minima on either side, so that flat ripples are not counted while a peak at the end
    of the sweep still is (without an AF when its half-power band is cut off).
    """
    s = np.asarray(speeds, dtype=float)
    a = np.abs(np.asarray(amplitude, dtype=float))
    if s.ndim != 1 or s.shape != a.shape or s.size < 3:
        raise ValueError("`speeds` and `amplitude` must be 1-D, of the same length >= 3")
    if np.any(np.diff(s) <= 0):
        raise ValueError("`speeds` must increase strictly")
    if operating is not None and not operating[0] <= operating[1]:
        raise ValueError(f"`operating` must be (N_min, N_max) with N_min <= N_max, got {operating}")
    out = []
    for i in range(1, s.size - 1):
        if not (a[i] > a[i - 1] and a[i] >= a[i + 1]):
            continue
        left, right = a[: i + 1].min(), a[i:].min()
        if a[i] - min(left, right) < prominence * a[i]:
            continue
        # parabola through the three samples around the maximum
        x0, x1, x2 = s[i - 1 : i + 2]
        y0, y1, y2 = a[i - 1 : i + 2]
        den = (x0 - x1) * (x0 - x2) * (x1 - x2)
        A = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / den
        B = (x2 * x2 * (y0 - y1) + x1 * x1 * (y2 - y0) + x0 * x0 * (y1 - y2)) / den
        if A < 0:
            peak_s = -B / (2 * A)
            peak_a = y1 + (A * peak_s * peak_s + B * peak_s) - (A * x1 * x1 + B * x1)
        else:
            peak_s, peak_a = x1, y1
        level = peak_a / np.sqrt(2.0)
        lo, hi = _crossing(s, a, level, i, -1), _crossing(s, a, level, i, +1)
        af = float(peak_s / (hi - lo)) if lo is not None and hi is not None and hi > lo else None
        margin = required = None
        if operating is not None:
            margin, required = separation_margin(float(peak_s), af, operating)
        inside = int(((s > lo) & (s < hi)).sum()) if af is not None else 0
        out.append(Peak(float(peak_s), float(peak_a), lo, hi, af, margin, required, inside))
    return out


def separation_margin(
    speed: float, af: float | None, operating: tuple[float, float]
) -> tuple[float, float]:
    """``(margin, required)`` of a resonance at ``speed`` with amplification factor ``af``
    from the operating range ``(N_min, N_max)``: the distance to the nearest operating limit
    as a fraction of it (negative inside the range) and what API 617 requires.

    >>> [round(x, 4) for x in separation_margin(80.0, 10.0, (100.0, 120.0))]
    [0.2, 0.15]
    """
    n_min, n_max = operating
    if speed < n_min:
        return (n_min - speed) / n_min, required_margin(af, True)
    if speed > n_max:
        return (speed - n_max) / n_max, required_margin(af, False)
    margin = -min(speed - n_min, n_max - speed) / max(n_max, 1e-300)
    return margin, required_margin(af, speed - n_min < n_max - speed)


def refinement_speeds(
    peak: Peak, speeds: np.ndarray, samples: int = MIN_BAND_SAMPLES
) -> np.ndarray:
    """Speeds to add around an unresolved ``peak`` of a response sampled at ``speeds`` so
    that its half-power band holds about ``samples + 3`` of them: spaced by the band's width
    (as estimated; between the peak's neighbouring samples when it has none) over
    ``samples + 3``, over 1.5 bands centred on the peak; speeds already sampled left out.

    >>> w = np.array([50.0, 90.0, 100.0, 110.0, 150.0])
    >>> p = Peak(100.0, 1.0, 95.0, 105.0, 10.0, samples=1)
    >>> new = refinement_speeds(p, w)
    >>> new.size, float(new.min()), float(new.max()), bool(np.all(np.diff(new) > 0))
    (12, 92.5, 107.5, True)
    """
    s = np.sort(np.asarray(speeds, dtype=float))
    if peak.lower is not None and peak.upper is not None and peak.upper > peak.lower:
        band = peak.upper - peak.lower
    else:
        i = int(np.argmin(np.abs(s - peak.speed)))
        band = float(s[min(i + 1, s.size - 1)] - s[max(i - 1, 0)]) / 2
    step = band / (samples + 3)
    grid = peak.speed + step * np.arange(-round(0.75 * band / step), round(0.75 * band / step) + 1)
    grid = grid[(grid > 0) & (grid >= s[0]) & (grid <= s[-1])]
    near = np.abs(grid[:, None] - s[None, :]).min(axis=1) < 1e-9 * max(float(s[-1]), 1.0)
    return np.asarray(grid[~near])
