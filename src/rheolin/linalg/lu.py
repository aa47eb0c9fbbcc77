"""``A0(n)^-1`` by LU factorizations: one sparse (PARDISO, UMFPACK or SuperLU) or LAPACK factor
per harmonic, or one batched LAPACK call over every harmonic of a small dense system."""

from __future__ import annotations

import logging
import warnings
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import scipy.linalg as sla

from .errors import SingularBlockError
from .pencil import Pencil
from .pool import map_chunks
from .store import FactorStore

__all__ = ["BatchedLUInverse", "LUInverse"]

log = logging.getLogger(__name__)

#: A pivot below this times the largest is round-off: the block is singular.
_PIVOT_RTOL = 1e3 * np.finfo(float).eps

Solver = Callable[[np.ndarray], np.ndarray]


def _dense_factor(pencil: Pencil, n: int) -> Solver:
    A = pencil.matrix(n)
    lu_piv = _lu_factor(A)
    d = np.abs(np.diag(lu_piv[0]))
    if d.min() <= _PIVOT_RTOL * d.max():
        raise SingularBlockError(n, "pivot below round-off")

    def solve_dense(r: np.ndarray, f: Any = lu_piv) -> np.ndarray:
        return np.asarray(sla.lu_solve(f, r.astype(complex), check_finite=False))

    return solve_dense


def _lu_factor(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """LAPACK LU (batched over leading axes); singular pivots are checked by the caller."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sla.LinAlgWarning)
        lu, piv = sla.lu_factor(A, check_finite=False)
    return lu, piv


def _nonzero_rows(R: np.ndarray) -> np.ndarray:
    return np.flatnonzero(np.any(R != 0, axis=1))


class LUInverse:
    """One LU factor of ``A0(n)`` per harmonic.

    Sparse pencils go through a :class:`~rheolin.linalg.store.FactorStore` (the sparse
    backend ``sparse_backend``, one symbolic analysis for every harmonic, factors held
    within ``budget`` bytes and refactorized on demand beyond it); dense ones through LAPACK.
    ``workers > 1`` runs the per-harmonic work on the shared long-lived pool.
    """

    name = "lu"
    exact = True

    def __init__(
        self,
        pencil: Pencil,
        ns: np.ndarray,
        workers: int = 1,
        sparse_backend: str = "auto",
        budget: int | None = None,
    ) -> None:
        self.pencil, self.ns, self.workers = pencil, np.asarray(ns), int(workers)
        self.store: FactorStore | None = None
        self._factors: list[Solver] = []
        if pencil.sparse:
            self.store = FactorStore(pencil, self.ns, sparse_backend, budget, self.workers)
            if not self.store.on_demand:  # factorize now, as the dense path does
                self.store.each(np.arange(self.ns.size), lambda i, f: None)
            self.sparse_backend = self.store.name
            return
        factors: list[Solver | None] = [None] * len(self.ns)

        def run(chunk: Sequence[int]) -> None:
            for i in chunk:
                factors[i] = _dense_factor(pencil, int(self.ns[i]))

        map_chunks(run, len(factors), self.workers)
        self._factors = factors  # type: ignore[assignment]
        log.debug("factorized %d blocks of size %d", len(factors), pencil.n)

    def _each(self, idx: np.ndarray, fn: Callable[[int, Solver], None]) -> None:
        if self.store is not None:
            self.store.each(idx, lambda i, f: fn(i, f.solve))
            return

        def run(chunk: Sequence[int]) -> None:
            for j in chunk:
                fn(int(idx[j]), self._factors[int(idx[j])])

        map_chunks(run, idx.size, self.workers)

    def solve(self, R: np.ndarray) -> np.ndarray:
        """``A0(n)^-1 r_n`` for every row (harmonic) of ``R``; zero rows stay zero."""
        out = np.zeros_like(R, dtype=complex)

        def one(i: int, solve: Solver) -> None:
            out[i] = solve(R[i])

        self._each(_nonzero_rows(R), one)
        return out

    def restricted(self, rows: np.ndarray, cols: np.ndarray) -> Solver:
        """``Z -> (A0(n)^-1[rows, cols] z_n)_n``: the blocks made once by unit solves."""
        E = np.zeros((self.pencil.n, cols.size), dtype=complex)
        E[cols, np.arange(cols.size)] = 1.0
        G = np.empty((self.ns.size, rows.size, cols.size), dtype=complex)

        def one(i: int, solve: Solver) -> None:
            G[i] = solve(E)[rows]

        self._each(np.arange(self.ns.size), one)
        return lambda Z: np.einsum("hij,hj->hi", G, Z)


class BatchedLUInverse:
    """Dense LU of every ``A0(n)`` at once (one batched LAPACK call).

    For small systems, where SuperLU's per-call overhead exceeds the arithmetic.
    """

    name = "dense"
    exact = True

    def __init__(self, pencil: Pencil, ns: np.ndarray) -> None:
        self.pencil, self.ns = pencil, np.asarray(ns)
        K, D, M = pencil.dense()
        s = pencil.s(self.ns)[:, None, None]
        A = K[None] + s * D[None] + (s * s) * M[None]
        self._lu, self._piv = _lu_factor(A)
        d = np.abs(np.diagonal(self._lu, axis1=1, axis2=2))
        bad = np.flatnonzero(d.min(axis=1) <= _PIVOT_RTOL * d.max(axis=1))
        if bad.size:
            raise SingularBlockError(int(self.ns[bad[0]]), "pivot below round-off")

    def _solve(self, idx: np.ndarray, B: np.ndarray) -> np.ndarray:
        return np.asarray(
            sla.lu_solve((self._lu[idx], self._piv[idx]), B, check_finite=False), dtype=complex
        )

    def solve(self, R: np.ndarray) -> np.ndarray:
        """``A0(n)^-1 r_n`` for every row (harmonic) of ``R``; zero rows stay zero."""
        out = np.zeros_like(R, dtype=complex)
        idx = _nonzero_rows(R)
        if idx.size:
            out[idx] = self._solve(idx, R[idx].astype(complex)[..., None])[..., 0]
        return out

    def restricted(self, rows: np.ndarray, cols: np.ndarray) -> Solver:
        """``Z -> (A0(n)^-1[rows, cols] z_n)_n`` from batched unit solves."""
        E = np.zeros((self.ns.size, self.pencil.n, cols.size), dtype=complex)
        E[:, cols, np.arange(cols.size)] = 1.0
        G = self._solve(np.arange(self.ns.size), E)[:, rows]
        return lambda Z: np.einsum("hij,hj->hi", G, Z)
