"""The edges of an unstable speed range, from verdicts one would defend.

Between a speed whose verdict is decided stable and one decided unstable, the largest Floquet
real part crosses zero. :func:`refine_edge` narrows that bracket where every evaluation is a
full, decided Floquet verdict: regula falsi (the Illinois variant) with each estimate moved
0.4 tolerances towards the end the last step left in place (once the estimate is that
accurate, the evaluation lands past the crossing and the bracket itself closes, not only the
estimate), and a bisection whenever two evaluations
have not halved the bracket (the real part is not smooth at an edge: flat at the mode's
damping on the stable side, rising like a square root past the lock of a parametric
resonance). The edge is the secant root in the final bracket and its uncertainty the
distance to the bracket's farther end: the crossing lies between a speed decided stable and
one decided unstable.

Where an evaluation is undecided (the crossing within the exponent's stated uncertainty), the
search brackets that zone from both sides (at twice the uncertainty over the slope, then four
times farther) and stops there: that bracket is the stated uncertainty.

(A partial search near the growing exponent, ``floquet(..., near=...)``, is cheaper but not a
verdict: nothing checks the exponents it leaves out or its truncation; docs/stability.md.)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["MAX_EVALUATIONS", "MAX_UNDECIDED", "Edge", "refine_edge", "states", "unstable_runs"]

#: Probes beyond the first on each side of an undecided zone (each four times farther).
MAX_UNDECIDED = 3

#: Each estimate is moved this many tolerances towards the bracket's far end: once it is
#: that accurate, the evaluation lands past the crossing and the bracket closes.
OVERSHOOT = 0.4

#: At most this many evaluations per edge (bisection alone reaches 1e-8 of a 10 % bracket in
#: 24).
MAX_EVALUATIONS = 40


@dataclass(frozen=True)
class Edge:
    """A range edge: ``speed`` with its ``uncertainty`` [rad/s], the final bracket
    (``stable_side``, ``unstable_side``: speeds whose verdicts are decided), the number of
    Floquet verdicts it took and how many of them were undecided."""

    speed: float
    uncertainty: float
    stable_side: float
    unstable_side: float
    evaluations: int
    undecided: int = 0


def refine_edge(
    verdict: Callable[[float], Any],
    stable: tuple[float, Any],
    unstable: tuple[float, Any],
    rtol: float,
) -> Edge:
    """The speed between ``stable`` and ``unstable`` (``(speed, FloquetResult)``, decided
    verdicts) where the largest real part crosses zero, to ``rtol`` relative: the final
    bracket between a decided stable and a decided unstable verdict is at most ``rtol``
    times the speed wide, unless an undecided zone stops it (module docstring).

    ``verdict(speed)`` returns the :class:`~rheolin.FloquetResult` at a speed. ``rtol = 0``:
    no evaluation; the edge is the unstable sample, uncertain by the bracket.

    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> def verdict(w):  # a growth rate crossing zero at 100 rad/s, decided off +-1e-6
    ...     re = 0.5 * (w - 100.0) + 0.01 * (w - 100.0) ** 2
    ...     return SimpleNamespace(max_real=re, stable=re < 0, decided=abs(re) > 1e-6,
    ...                            max_real_uncertainty=1e-6)
    >>> e = refine_edge(verdict, (95.0, verdict(95.0)), (104.0, verdict(104.0)), 1e-7)
    >>> bool(abs(e.speed - 100.0) <= e.uncertainty <= 1e-5), e.evaluations
    (True, 4)
    """
    a, ra = stable
    b, rb = unstable
    a, b = float(a), float(b)
    count = undecided = 0
    if not (rtol > 0 and ra.decided and rb.decided and ra.stable and not rb.stable):
        return Edge(b, abs(b - a), a, b, count)
    raw_a, raw_b = _below(ra.max_real), _above(rb.max_real)
    fa, fb = raw_a, raw_b  # Illinois-weighted copies
    xtol = rtol * max(abs(a), abs(b))
    side = 0  # which end the last evaluation moved: -1 the stable one, +1 the unstable one
    widths = [abs(b - a)]
    while abs(b - a) > xtol and count < MAX_EVALUATIONS:
        lo, hi = min(a, b), max(a, b)
        x = (a * fb - b * fa) / (fb - fa)
        if side:  # a little past the estimate towards the end the last step left in place
            far = b if side == -1 else a
            x += np.sign(far - x) * OVERSHOOT * xtol
        if len(widths) >= 3 and widths[-1] > 0.5 * widths[-3]:
            x = 0.5 * (a + b)  # two evaluations have not halved the bracket
        margin = min(0.25 * xtol, 0.25 * (hi - lo))
        x = float(np.clip(x, lo + margin, hi - margin))
        res = verdict(x)
        count += 1
        if not res.decided:
            undecided += 1
            a, b, fa, fb, more, extra = _around_undecided(verdict, x, res, a, b, raw_a, raw_b, xtol)
            raw_a, raw_b = fa, fb
            count += more
            undecided += extra
            break
        if res.stable:
            a, fa = x, _below(res.max_real)
            raw_a = fa
            if side == -1:
                fb *= 0.5  # Illinois: the retained end's value halved
            side = -1
        else:
            b, fb = x, _above(res.max_real)
            raw_b = fb
            if side == 1:
                fa *= 0.5
            side = 1
        widths.append(abs(b - a))
    lo, hi = min(a, b), max(a, b)
    speed = float(np.clip((a * raw_b - b * raw_a) / (raw_b - raw_a), lo, hi))
    return Edge(speed, max(speed - lo, hi - speed), a, b, count, undecided)


def _around_undecided(
    verdict: Callable[[float], Any],
    x: float,
    res: Any,
    a: float,
    b: float,
    fa: float,
    fb: float,
    xtol: float,
) -> tuple[float, float, float, float, int, int]:
    """Bracket the undecided zone around ``x`` (inside ``a``..``b``) by decided verdicts:
    ``(a, b, f(a), f(b), evaluations, undecided ones)``."""
    slope = abs(fb - fa) / max(abs(b - a), 1e-300)
    unc = float(getattr(res, "max_real_uncertainty", float("nan")))
    step = 2.0 * unc / slope if np.isfinite(unc) and slope > 0 else xtol
    step = max(step, OVERSHOOT * xtol)
    count = undecided = 0
    for toward in (a, b):
        d = step
        for _ in range(MAX_UNDECIDED + 1):
            y = x + float(np.sign(toward - x)) * d
            if not min(a, b) < y < max(a, b):
                break
            r = verdict(y)
            count += 1
            if r.decided:
                if r.stable and toward == a:
                    a, fa = y, _below(r.max_real)
                elif not r.stable and toward == b:
                    b, fb = y, _above(r.max_real)
                break
            undecided += 1
            d *= 4.0
    return a, b, fa, fb, count, undecided


def states(stable: np.ndarray, decided: np.ndarray) -> np.ndarray:
    """Per speed ``"stable"``, ``"unstable"`` or ``"undecided"`` from the verdicts.

    >>> states(np.array([True, False, True]), np.array([True, True, False])).tolist()
    ['stable', 'unstable', 'undecided']
    """
    stable, decided = np.asarray(stable, bool), np.asarray(decided, bool)
    return np.where(~decided, "undecided", np.where(stable, "stable", "unstable"))


def unstable_runs(state: np.ndarray) -> list[tuple[int, int]]:
    """``(first, last)`` of each run of samples not decided stable that holds a decided
    unstable one (an undecided sample alone is not a range: it is reported as undecided)."""
    out = []
    i = 0
    while i < state.size:
        if state[i] == "stable":
            i += 1
            continue
        j = i
        while j + 1 < state.size and state[j + 1] != "stable":
            j += 1
        if np.any(state[i : j + 1] == "unstable"):
            out.append((i, j))
        i = j + 1
    return out


def _below(x: float) -> float:
    return min(float(x), -1e-300)


def _above(x: float) -> float:
    return max(float(x), 1e-300)
