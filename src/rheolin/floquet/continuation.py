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
and so does everything after a change of model size.

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

__all__ = ["Continuation"]


class Continuation:
    """The lattice eigenvectors of the last :func:`~rheolin.floquet` call, per lattice.

    Holds one :class:`~rheolin.floquet.LatticeExponents` per lattice order seen (their
    eigenvectors: a few MB for a gearbox); :meth:`clear` forgets them.
    """

    def __init__(self) -> None:
        self._kept: dict[tuple[int, int], tuple[np.ndarray, LatticeExponents]] = {}

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
