"""``A0(n)^-1`` by LU factorizations: one SuperLU (or LAPACK) factor per harmonic, or one
batched LAPACK call over every harmonic of a small dense system."""

from __future__ import annotations

import functools
import logging
import warnings
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla

from .errors import SingularBlockError
from .pencil import Pencil
from .pool import map_chunks

__all__ = ["SPLU_OPTIONS", "BatchedLUInverse", "LUInverse"]

log = logging.getLogger(__name__)

#: SuperLU options for the per-harmonic blocks. Structural matrices are structurally
#: symmetric; threshold pivoting that prefers the diagonal keeps the fill of the symmetric
#: ordering. Partial pivoting (SuperLU's default) multiplied the fill by 80 on indefinite
#: mid-range harmonics of a chain (3.8e6 vs 4.7e4 entries, 1.6 s vs 10 ms per factor).
#: The recomputed residual of every solution guards the accuracy.
SPLU_OPTIONS: dict[str, Any] = {
    "permc_spec": "MMD_AT_PLUS_A",
    "diag_pivot_thresh": 0.1,
    "options": {"SymmetricMode": True},
}

#: A pivot below this times the largest is round-off: the block is singular.
_PIVOT_RTOL = 1e3 * np.finfo(float).eps

Solver = Callable[[np.ndarray], np.ndarray]


@functools.lru_cache(maxsize=8)
def _probe_vector(size: int) -> np.ndarray:
    """A fixed random right-hand side that checks each factorization (made once per size)."""
    b = np.random.default_rng(size).standard_normal(size)
    b.setflags(write=False)
    return b


def _splu_checked(A: Any, n: int) -> Any:
    """Sparse LU with diagonal-preferring pivoting, checked; partial pivoting if inaccurate."""
    b = _probe_vector(A.shape[0])
    for options in (SPLU_OPTIONS, {"permc_spec": "MMD_AT_PLUS_A"}):
        try:
            lu = spla.splu(A, **options)
        except RuntimeError as exc:
            raise SingularBlockError(n, str(exc)) from None
        diag = np.abs(lu.U.diagonal())
        if diag.size and diag.min() <= _PIVOT_RTOL * diag.max():
            raise SingularBlockError(n, "pivot below round-off")
        x = lu.solve(b.astype(A.dtype))
        if np.linalg.norm(A @ x - b) <= 1e-11 * np.linalg.norm(b):
            return lu
        log.debug("A0(%d): threshold pivoting inaccurate; refactorizing", n)
    return lu


def _factor(pencil: Pencil, n: int) -> Solver:
    A = pencil.matrix(n)
    if pencil.sparse:
        lu = _splu_checked(A, n)
        if np.isrealobj(A):

            def solve_real(r: np.ndarray, lu: Any = lu) -> np.ndarray:
                if r.ndim == 1:
                    both = lu.solve(np.column_stack([r.real, r.imag]))
                    return both[:, 0] + 1j * both[:, 1]
                return lu.solve(np.ascontiguousarray(r.real)) + 1j * lu.solve(
                    np.ascontiguousarray(r.imag)
                )

            return solve_real

        def solve_complex(r: np.ndarray, lu: Any = lu) -> np.ndarray:
            return np.asarray(lu.solve(r.astype(complex)))

        return solve_complex
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
    """One LU factor of ``A0(n)`` per harmonic (SuperLU when sparse, LAPACK when dense).

    ``workers > 1`` runs the factorizations and solves on the shared long-lived pool.
    """

    name = "lu"
    exact = True

    def __init__(self, pencil: Pencil, ns: np.ndarray, workers: int = 1) -> None:
        self.pencil, self.ns, self.workers = pencil, np.asarray(ns), int(workers)
        factors: list[Solver | None] = [None] * len(self.ns)

        def run(chunk: Sequence[int]) -> None:
            for i in chunk:
                factors[i] = _factor(pencil, int(self.ns[i]))

        map_chunks(run, len(factors), self.workers)
        self._factors: list[Solver] = factors  # type: ignore[assignment]
        log.debug("factorized %d blocks of size %d", len(factors), pencil.n)

    def _each(self, idx: np.ndarray, fn: Callable[[int], None]) -> None:
        def run(chunk: Sequence[int]) -> None:
            for j in chunk:
                fn(int(idx[j]))

        map_chunks(run, idx.size, self.workers)

    def solve(self, R: np.ndarray) -> np.ndarray:
        """``A0(n)^-1 r_n`` for every row (harmonic) of ``R``; zero rows stay zero."""
        out = np.zeros_like(R, dtype=complex)

        def one(i: int) -> None:
            out[i] = self._factors[i](R[i])

        self._each(_nonzero_rows(R), one)
        return out

    def restricted(self, rows: np.ndarray, cols: np.ndarray) -> Solver:
        """``Z -> (A0(n)^-1[rows, cols] z_n)_n``: the blocks made once by unit solves."""
        E = np.zeros((self.pencil.n, cols.size), dtype=complex)
        E[cols, np.arange(cols.size)] = 1.0
        G = np.empty((self.ns.size, rows.size, cols.size), dtype=complex)

        def one(i: int) -> None:
            G[i] = self._factors[i](E)[rows]

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
