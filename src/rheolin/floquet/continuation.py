"""Continuation of the lattice search over a sweep: each call starts from the last one.

Over a fine speed grid the Floquet exponents and their eigenvectors move little from one speed
to the next. A :class:`Continuation` passed to :func:`rheolin.floquet` keeps the lattice
exponents and eigenvectors of each call (one set per lattice order, the finer lattices'
confirmations included). The next call matches its clusters of time-averaged exponents to the
previous ones and *tracks* each matched cluster's exponents: moved by the cluster's averaged
shift and polished there (an LU and three solves, no Arnoldi run). They are kept only when
they pass the tests a search's exponents pass (converged to a backward error of 1e-10, which
enters their bounds; centred, or the same off-centre copy as before, moving slowly; standing
for their own cluster; meeting its quota as distinct exponents); any other cluster is
searched, starting from the previous eigenvectors (a confirmation's cluster unresolved at the
previous speed from this speed's coarse vectors: an unresolved exponent's continuation is
unresolved again). The checks of the verdict are
those of a call without one (docs/stability.md, section 5). An unmatched cluster starts cold,
and so does everything after a change of model size. The matching is :func:`previous_rows`;
the start vectors (from the previous speed, or from a coarser lattice of the same system) are
:func:`warm_start`'s; the tracking itself is
:meth:`~rheolin.floquet.search.LatticeSearch.track_cluster`.

>>> import numpy as np, rheolin as rl
>>> from rheolin.floquet import Continuation
>>> cont = Continuation()
>>> def mathieu(w):  # a pumped oscillator: time variation at 2 w
...     return rl.PeriodicSystem(2 * w, M={0: np.eye(1)}, D={0: 0.1 * np.eye(1)},
...                              K={0: np.eye(1), 1: -0.1 * np.eye(1)})
>>> a = rl.floquet(mathieu(1.3), method="lattice", order=4, continuation=cont)
>>> b = rl.floquet(mathieu(1.31), method="lattice", order=4, continuation=cont)
>>> c = rl.floquet(mathieu(1.31), method="lattice", order=4)
>>> b.info["tracked"], b.info["shifts"], bool(abs(b.max_real - c.max_real) < 1e-9)
(1, 0, True)
"""

from __future__ import annotations

import copy

import numpy as np

from ..harmonics.lattice import Lattice
from .outcome import LatticeExponents
from .select import CLUSTER_TOL

__all__ = ["TRACK_DRIFT", "TRACK_POLISH", "TRACK_TOL", "WARM_OVERLAP", "Continuation"]


#: Tracking (a search continued from the previous speed on the same lattice): each of a
#: cluster's previous representatives is moved by its cluster's averaged shift and polished
#: there (one LU, three solves: no Arnoldi run). Accepted when every one converges to a
#: backward error below this (relative, of the balanced first-order pencil), is centred (or
#: the same off-centre copy as before: :data:`TRACK_DRIFT`) and stands for its cluster only,
#: and together they meet the cluster's quota as distinct exponents (the test a search
#: meets); otherwise the cluster is searched.
TRACK_TOL = 1e-10

#: Polish steps (an LU each) a tracked exponent may take to meet :data:`TRACK_TOL`: the
#: averaged shift predicts it closely, but one step does not always reach that backward
#: error (bench/stability.py, design notes).
TRACK_POLISH = 2

#: An off-centre representative (centroid above :data:`~rheolin.floquet.select.CENTRED`: its
#: energy split between harmonic 0 and its neighbours, a mode coupled strongly through the
#: time variation) is tracked as well when it stays the same copy of the same exponent: its
#: centroid moves by at most ``TRACK_DRIFT`` and its real part by at most ``TRACK_DRIFT`` of
#: its distance from the axis (a copy changing places, or a resonance setting in, moves them
#: faster; the cluster is then searched). Copies of one exponent share its real part, so the
#: copy kept does not change the verdict; its truncation is judged as a search's would be
#: (unresolved: by the discs or a finer lattice).
TRACK_DRIFT = 0.05

#: A warm-started search ends when every coarse eigenvector has a converged Ritz vector at
#: least this close (|cos| of the angle between them).
WARM_OVERLAP = 0.5


class Continuation:
    """The lattice eigenvectors of the last :func:`~rheolin.floquet` call, per lattice.

    Holds one :class:`~rheolin.floquet.LatticeExponents` per lattice order seen (their
    eigenvectors: a few MB for a gearbox); :meth:`clear` forgets them. ``rtol``: the accuracy
    of the largest real part the calls that share it ask for (:func:`rheolin.floquet`'s
    ``rtol`` when a call gives none; None: no refinement), so that a sweep's settings reach
    every verdict.
    """

    def __init__(self, rtol: float | None = None) -> None:
        self._kept: dict[tuple[int, int], tuple[np.ndarray, LatticeExponents]] = {}
        self._band: tuple[int, int] | None = None
        self.rtol = rtol

    def band_start(self, n: int) -> int | None:
        """The band size the last certified band of a system of ``n`` DOFs was asked for
        (None: none): the next speed's band starts there, not at the smallest size that the
        last speed already outgrew (:func:`~rheolin.floquet.band.band_modes`)."""
        return self._band[1] if self._band is not None and self._band[0] == n else None

    def keep_band(self, n: int, asked: int | None) -> None:
        """Remember the size a certified band of ``n`` DOFs was asked for (None: forget)."""
        self._band = None if asked is None else (n, int(asked))

    def start(self, n: int, lattice: Lattice) -> LatticeExponents | None:
        """The kept search on ``lattice`` for a system of ``n`` DOFs (None: none)."""
        got = self._kept.get((n, lattice.order))
        if got is None or not np.array_equal(got[0], lattice.indices):
            return None
        return got[1]

    def keep(self, n: int, lattice: Lattice, out: LatticeExponents) -> None:
        """Keep a search's result as it is now (a later confirmation on a finer lattice
        replaces some of its fields: the copy keeps these)."""
        kept = copy.copy(out)
        kept.settle = None  # pending truncation estimates are not continued
        self._kept[(n, lattice.order)] = (lattice.indices.copy(), kept)

    def clear(self) -> None:
        """Forget every kept search (the next call starts cold)."""
        self._kept.clear()

    @property
    def nbytes(self) -> int:
        """Memory of the kept eigenvectors [bytes] (a verdict's estimate counts it: on a
        large model the finer lattices' vectors are the larger part)."""
        return sum(
            int(v.nbytes) for _, out in self._kept.values() for v in out.vectors if v is not None
        )


def warm_start(
    start: LatticeExponents | None,
    H: np.ndarray,
    n: int,
    sigma: complex,
    w: float,
    rng: np.random.Generator,
    resolved: bool = False,
    rows: tuple[list[int], complex] | None = None,
) -> tuple[np.ndarray | None, complex]:
    """The coarse eigenvectors of the cluster centred at ``sigma``, moved onto the harmonics
    ``H`` with random weights, one per column, and the mean of their exponents (None: none
    known). ``rows``: the rows of ``start`` standing for this cluster and the shift of its
    averaged exponents since (another system's start, :func:`previous_rows`); else those
    whose cluster centre is ``sigma`` (the same system's)."""
    if start is None or not start.vectors:
        return None, sigma
    tol = CLUSTER_TOL * max(abs(sigma), w)
    Hc = start.indices
    pos = np.searchsorted(H, Hc)
    if np.any(pos >= H.size) or np.any(H[np.minimum(pos, H.size - 1)] != Hc):
        return None, sigma  # not a sub-lattice
    nh, nc = H.size, Hc.size
    cols = (pos[:, None] * n + np.arange(n)).ravel()
    if rows is not None:
        candidates, moved = rows
    else:
        candidates = [i for i, z in enumerate(start.centre) if abs(z - sigma) <= tol]
        moved = 0j
    mine = [
        i
        for i in candidates
        if start.vectors[i] is not None and not (resolved and start.unresolved[i])
    ]
    if not mine:
        return None, sigma
    picked = [v for v in (start.vectors[i] for i in mine) if v is not None]
    out = np.zeros((2 * n * nh, len(picked)), dtype=complex)
    for j, v in enumerate(picked):
        c = complex(rng.standard_normal(), rng.standard_normal())
        out[cols, j] = c * v[: n * nc]
        out[n * nh + cols, j] = c * v[n * nc :]
    return out / np.linalg.norm(out), complex(np.mean(start.exponents[mine])) + moved


def previous_rows(
    start: LatticeExponents, lam0: np.ndarray, members: np.ndarray, w: float
) -> tuple[list[int], complex]:
    """The rows of ``start`` (a nearby system's search: the previous speed) standing for the
    cluster of averaged exponents ``lam0[members]`` (all of them in ``lam0``, conjugates
    included), and how far the cluster's centre moved since (``([], 0)``: no unambiguous
    match).

    The previous cluster is the one whose centre is nearest this centre, when it moved by
    less than ``CLUSTER_TOL`` (relative), or by less than half the distance to any other
    averaged exponent and less than the previous centre's distance to any of them (no other
    exponent can have come from there).
    """
    have = [i for i, v in enumerate(start.vectors) if v is not None]
    if not have:
        return [], 0j
    sigma = complex(np.mean(lam0[members]))
    prev = np.unique(start.centre[have])
    prev = prev[np.isfinite(prev)]
    if not prev.size:
        return [], 0j
    j = int(np.argmin(np.abs(prev - sigma)))
    zp, d = complex(prev[j]), float(np.abs(prev[j] - sigma))
    if d > CLUSTER_TOL * max(abs(sigma), w):
        # every other averaged exponent (the conjugates are among them)
        others = np.ones(lam0.size, dtype=bool)
        others[members] = False
        rest = lam0[others]
        gap = float(np.min(np.abs(rest - sigma))) if rest.size else np.inf
        to_prev = float(np.min(np.abs(rest - zp))) if rest.size else np.inf
        if not (d < 0.5 * gap and d < to_prev):
            return [], 0j
    return [i for i in have if start.centre[i] == zp], sigma - zp
