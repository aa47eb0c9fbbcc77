"""The edges of an unstable speed range, from verdicts one would defend.

Between a speed whose verdict is decided stable and one decided unstable, the largest Floquet
real part crosses zero. :func:`refine_edge` narrows that bracket with full Floquet verdicts.
Only the unstable side says where the edge is: there the growing exponent's real part rises
from zero, like ``sqrt(W - W_e)`` past the lock of a parametric resonance and linearly where
one exponent crosses the axis alone. On the stable side the largest real part belongs to a
mode's damping (flat) or to a marginal exponent on the axis, and says nothing. So the two
unstable evaluations nearest the edge estimate it. Three of them give the speed as a
quadratic in the growth rate, at zero growth: exact for a linear crossing, a square root and a
damped one (``C sqrt(W - W_0) - d``). Two give the root of the secant through their real
parts (``x_lin``, exact for a linear crossing, on the stable side of a square root) and
through their squares (``x_sq``, exact for a square root, on the unstable side of a linear
crossing), which bracket the edge for every growth between the two: after a stable
evaluation the next one is at ``x_sq``, after an unstable one at ``x_lin``. Each estimate is
moved 0.4
tolerances towards the end the last step left in place (once an estimate is that accurate,
the evaluation lands past the crossing and the bracket itself closes), with a bisection
whenever two evaluations have not halved the bracket.

An undecided evaluation (the crossing within the exponent's stated uncertainty) still moves
the bracket by the side it leans to, so the edge is found to the tolerance; its uncertainty
is measured from the nearest speeds *decided* stable and unstable. When the final bracket
ends on undecided verdicts, the search probes outwards from the edge (at twice the
uncertainty over the slope, then four times farther) for decided ones. The edge is the
midpoint of the final bracket.

(A partial search near the growing exponent, ``floquet(..., near=...)``, is cheaper but not a
verdict: nothing checks the exponents it leaves out or its truncation; docs/stability.md.)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..floquet import Continuation, FloquetResult
from ..floquet.result import guarded

__all__ = [
    "EDGE_RTOL",
    "MAX_EVALUATIONS",
    "MAX_UNDECIDED",
    "Edge",
    "edge_between",
    "refine_edge",
    "states",
    "unstable_runs",
]

#: Accuracy of the leading exponent asked of an edge's verdict left undecided by its lattice
#: (at most: a third of its real part is enough to decide it).
EDGE_RTOL = 0.1

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
    """A range edge: ``speed`` with its ``uncertainty`` [rad/s], the nearest speeds whose
    verdicts are decided on either side (``stable_side``, ``unstable_side``), the number of
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
    bracket is at most ``rtol`` times the speed wide (module docstring).

    ``verdict(speed)`` returns the :class:`~rheolin.FloquetResult` at a speed. ``rtol = 0``:
    no evaluation; the edge is the unstable sample, uncertain by the bracket.

    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> def verdict(w):  # a parametric lock at 100 rad/s: flat stable side, a square root past it
    ...     re = 3.0 * np.sqrt(max(w - 100.0, 0.0)) - 0.2
    ...     return SimpleNamespace(max_real=re, stable=re < 0, decided=abs(re) > 1e-6,
    ...                            max_real_uncertainty=1e-6)
    >>> edge = 100.0 + (0.2 / 3.0) ** 2
    >>> e = refine_edge(verdict, (95.0, verdict(95.0)), (104.0, verdict(104.0)), 1e-7)
    >>> bool(abs(e.speed - edge) <= e.uncertainty <= 1e-5), e.evaluations <= 8
    (True, True)
    """
    a, ra = stable
    b, rb = unstable
    a, b = float(a), float(b)
    if not (rtol > 0 and ra.decided and rb.decided and ra.stable and not rb.stable):
        return Edge(b, abs(b - a), a, b, 0)
    xtol = rtol * max(abs(a), abs(b))
    dec_a, dec_b = a, b  # the nearest decided verdicts
    grow = [(b, float(rb.max_real))]  # unstable evaluations: the growth rate there
    count = undecided = 0
    side = 0  # which end the last evaluation moved: -1 the stable one, +1 the unstable one
    widths = [abs(b - a)]
    while abs(b - a) > xtol and count < MAX_EVALUATIONS:
        lo, hi = min(a, b), max(a, b)
        x = _estimate(grow, a, side)
        if x is None or not lo < x < hi:
            x = 0.5 * (a + b)
        elif side:  # a little past the estimate towards the end the last step left in place
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
        if not np.isfinite(res.max_real):  # no verdict there (a numerical failure): stop
            break
        if res.stable:
            a, side = x, -1
            if res.decided:
                dec_a = x
        else:
            b, side = x, 1
            grow.append((x, float(res.max_real)))
            if res.decided:
                dec_b = x
        widths.append(abs(b - a))
    speed = 0.5 * (a + b)
    if dec_a != a or dec_b != b:  # the bracket ends on undecided verdicts: look for decided ones
        dec_a, dec_b, more, extra = _around_undecided(
            verdict, speed, grow, dec_a, dec_b, a, b, xtol
        )
        count += more
        undecided += extra
    return Edge(speed, max(abs(speed - dec_a), abs(dec_b - speed)), dec_a, dec_b, count, undecided)


def _estimate(grow: list[tuple[float, float]], a: float, side: int) -> float | None:
    """The edge estimated from the unstable evaluations nearest the stable end ``a``: with
    three, the speed as a quadratic in the growth rate through them at zero growth (exact for
    a linear crossing, a square root and a damped square root ``C sqrt(W - W_0) - d``); with
    two, ``x_sq`` after a stable step, ``x_lin`` otherwise (module docstring). None when the
    growth does not fall towards ``a``."""
    near = sorted(grow, key=lambda p: abs(p[0] - a))[:3]
    w = np.array([p[0] for p in near])
    f = np.array([p[1] for p in near])
    if len(near) < 2 or not (np.all(f > 0) and np.all(np.diff(f) > 0)):
        return None
    if len(near) == 3:
        # Lagrange form of w(f) at f = 0
        x = 0.0
        for i in range(3):
            j, k = [m for m in range(3) if m != i]
            x += w[i] * f[j] * f[k] / ((f[i] - f[j]) * (f[i] - f[k]))
        return float(x)
    if side == -1:
        f = f * f
    return float(w[0] - f[0] * (w[0] - w[1]) / (f[0] - f[1]))


def _around_undecided(
    verdict: Callable[[float], Any],
    x: float,
    grow: list[tuple[float, float]],
    dec_a: float,
    dec_b: float,
    a: float,
    b: float,
    xtol: float,
) -> tuple[float, float, int, int]:
    """Probe outwards from the edge ``x`` for decided verdicts on the sides whose nearest
    decided one (``dec_a``, ``dec_b``) is farther than the bracket's end (``a``, ``b``):
    ``(dec_a, dec_b, evaluations, undecided ones)``."""
    slope = 0.0
    if len(grow) >= 2:
        (w1, f1), (w2, f2) = sorted(grow, key=lambda p: abs(p[0] - x))[:2]
        slope = abs(f2 - f1) / max(abs(w2 - w1), 1e-300)
    count = undecided = 0
    for want_stable, end, dec in ((True, a, dec_a), (False, b, dec_b)):
        if dec == end:
            continue
        d = max(abs(end - x), xtol)
        for _ in range(MAX_UNDECIDED + 1):
            y = x + float(np.sign(end - x)) * d
            if not min(dec, x) < y < max(dec, x):
                break
            r0 = verdict(y)
            count += 1
            if r0.decided and bool(r0.stable) == want_stable:
                if want_stable:
                    dec_a = y
                else:
                    dec_b = y
                break
            undecided += not r0.decided
            unc = float(getattr(r0, "max_real_uncertainty", float("nan")))
            if np.isfinite(unc) and slope > 0:
                d = max(d, 2.0 * unc / slope)
            d *= 4.0
    return dec_a, dec_b, count, undecided


def edge_between(
    run: Callable[..., tuple[Any, FloquetResult]],
    count: list[int],
    stable: tuple[float, FloquetResult],
    unstable: tuple[float, FloquetResult],
    refine: float,
) -> Any:
    """One range edge between two decided samples, every evaluation a full verdict continued
    from the previous one (its largest real part not refined: the verdict is what counts).

    Between two lattice verdicts the evaluations use the larger of their lattice orders
    (the edge's speeds need no more than its samples, except within the truncation
    uncertainty of the crossing). Where that order leaves a speed undecided, its leading
    exponent is refined near it until its uncertainty is a third of its real part, then the
    next order decides;
    a speed still undecided is bracketed by :func:`~rheolin.stability.ranges.refine_edge`.
    (The automatic verdict would climb through every order up to the one that decides, at
    ten times the cost.)"""
    cont = Continuation()
    orders = [_lattice_order(r) for r in (stable[1], unstable[1])]
    fixed = max(orders) if None not in orders else None  # type: ignore[type-var]

    def verdict(W: float) -> FloquetResult:
        res = guarded(checked, W)
        if res.method == "failed":  # no verdict there: refine_edge stops at it
            cont.clear()
        return res

    def checked(W: float) -> FloquetResult:
        count[0] += 1
        if fixed is None:  # the automatic verdict raises its own order where undecided
            return run(W, cont, float("inf"))[1]
        res = run(W, cont, float("inf"), fixed)[1]
        if not res.decided:  # the leading exponent refined near it, enough to decide
            count[0] += 1
            res = run(W, cont, _deciding_rtol(res), fixed)[1]
        if not res.decided:  # then the next order
            count[0] += 1
            res = run(W, cont, float("inf"), fixed + 1)[1]
        return res

    return refine_edge(
        verdict, (float(stable[0]), stable[1]), (float(unstable[0]), unstable[1]), refine
    )


def _deciding_rtol(res: FloquetResult) -> float:
    """An ``rtol`` that makes the leading exponent's uncertainty a third of its real part
    (the target of :func:`~rheolin.floquet.accuracy.target`), at most :data:`EDGE_RTOL`."""
    from ..floquet.accuracy import ZETA_FLOOR

    re, lam = abs(float(res.max_real)), complex(res.leading)
    if not (np.isfinite(re) and np.isfinite(lam)) or re == 0:
        return EDGE_RTOL
    return float(min(EDGE_RTOL, re / (3.0 * max(re, ZETA_FLOOR * abs(lam)))))


def _lattice_order(res: FloquetResult) -> int | None:
    """The order of the lattice a verdict was decided on (None: not a lattice verdict)."""
    lattice = getattr(res, "lattice", None)
    if res.method != "lattice" or lattice is None:
        return None
    return int(lattice.order)


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
