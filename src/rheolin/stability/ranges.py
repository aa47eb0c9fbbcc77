"""The edges of an unstable speed range, from verdicts one would defend.

Between a speed whose verdict is decided stable and one decided unstable, the largest Floquet
real part crosses zero. :func:`refine_edge` narrows that bracket by regula falsi (the Illinois
variant: superlinear on a smooth crossing, never slower than bisection by much) where every
evaluation is a full, decided Floquet verdict, each continued from the previous one
(:class:`~rheolin.floquet.Continuation`). The edge is the secant root in the final bracket and
its uncertainty the distance to the farther end: the crossing lies between a speed decided
stable and one decided unstable. Where an evaluation is undecided (the crossing within the
exponent's uncertainty), the search brackets that zone from both sides (at twice the
uncertainty over the slope, then four times wider) and stops: the bracket is the stated
uncertainty.

(A partial search near the growing exponent, ``floquet(..., near=...)``, is cheaper but not a
verdict: nothing checks the exponents it leaves out or its truncation; docs/stability.md.)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["MAX_UNDECIDED", "Edge", "refine_edge", "states", "unstable_runs"]

#: Probes beyond the first on each side of an undecided zone (each four times farther).
MAX_UNDECIDED = 4

#: At most this many evaluations per edge (bisection would reach 1e-8 of a 10 % bracket in 24).
MAX_EVALUATIONS = 40


@dataclass(frozen=True)
class Edge:
    """A range edge: ``speed`` with its ``uncertainty`` [rad/s], the final bracket
    (``stable_side``, ``unstable_side``: speeds whose verdicts are decided) and the number of
    Floquet verdicts it took."""

    speed: float
    uncertainty: float
    stable_side: float
    unstable_side: float
    evaluations: int


def refine_edge(
    verdict: Callable[[float], Any],
    stable: tuple[float, Any],
    unstable: tuple[float, Any],
    rtol: float,
) -> Edge:
    """The speed between ``stable`` and ``unstable`` (``(speed, FloquetResult)``, decided
    verdicts) where the largest real part crosses zero, to ``rtol`` relative.

    ``verdict(speed)`` returns the :class:`~rheolin.FloquetResult` at a speed. ``rtol = 0``:
    no evaluation; the edge is the unstable sample, uncertain by the bracket.

    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> def verdict(w):  # a growth rate crossing zero at 100 rad/s, decided off +-1e-6
    ...     re = 0.5 * (w - 100.0)
    ...     return SimpleNamespace(max_real=re, stable=re < 0, decided=abs(re) > 1e-6,
    ...                            max_real_uncertainty=1e-6)
    >>> e = refine_edge(verdict, (95.0, verdict(95.0)), (104.0, verdict(104.0)), 1e-9)
    >>> bool(abs(e.speed - 100.0) <= e.uncertainty <= 1e-5), e.evaluations
    (True, 3)
    """
    a, ra = stable
    b, rb = unstable
    count = 0
    if not (rtol > 0 and ra.decided and rb.decided and ra.stable and not rb.stable):
        return Edge(float(b), abs(float(b) - float(a)), float(a), float(b), count)
    fa, fb = _below(ra.max_real), _above(rb.max_real)
    xtol = rtol * max(abs(a), abs(b))
    side = 0
    while abs(b - a) > xtol and count < MAX_EVALUATIONS:
        lo, hi = min(a, b), max(a, b)
        guard = 0.01 * (hi - lo)  # regula falsi stays off the bracket's ends
        x = float(np.clip((a * fb - b * fa) / (fb - fa), lo + guard, hi - guard))
        res = verdict(x)
        count += 1
        if not res.decided:
            # the crossing within the exponent's uncertainty: bracket that zone from both
            # sides, at the distance the uncertainty and the slope suggest, then wider
            slope = abs(fb - fa) / max(hi - lo, 1e-300)
            unc = getattr(res, "max_real_uncertainty", float("nan"))
            step = 2.0 * unc / slope if np.isfinite(unc) and slope > 0 else xtol
            step = max(step, xtol)
            for toward in (a, b):
                d = step
                for _ in range(MAX_UNDECIDED + 1):
                    y = x + np.sign(toward - x) * d
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
                    d *= 4.0
            break
        if res.stable:
            a, fa = x, _below(res.max_real)
            if side == -1:
                fb *= 0.5  # Illinois: the retained end's value halved
            side = -1
        else:
            b, fb = x, _above(res.max_real)
            if side == 1:
                fa *= 0.5
            side = 1
    lo, hi = min(a, b), max(a, b)
    speed = float(np.clip((a * fb - b * fa) / (fb - fa), lo, hi))
    return Edge(speed, max(speed - lo, hi - speed), float(a), float(b), count)


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
