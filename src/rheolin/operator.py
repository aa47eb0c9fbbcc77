"""The harmonic-balance operator of a :class:`PeriodicSystem` on a :class:`HarmonicSet`.

Row ``m`` of the coupled system (DESIGN.md §2, seed eq. 3)::

    sum_{n in H} A_{m-n}(n) q_n = f_m,   A_k(n) = -(n w1)^2 M_k + i n w1 D_k + K_k

Only the half ``n >= 0`` is stored and solved (``q_{-n} = conj(q_n)`` for a real system).
``A0`` (the block diagonal, ``k = 0``) is factorized once per ``n >= 0``; the time-varying
part ``dA`` is applied as a sparse convolution over harmonic indices, never assembled.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .harmonics import HarmonicSet
from .system import PeriodicSystem

__all__ = ["HarmonicBalance", "SingularBlockError"]

log = logging.getLogger(__name__)


class SingularBlockError(RuntimeError):
    """``A0(n)`` could not be factorized (exactly singular: an undamped resonance)."""

    def __init__(self, n: int, detail: str) -> None:
        super().__init__(f"A0(n={n}) is singular ({detail})")
        self.n = n


def default_workers() -> int:
    """Threads for per-harmonic work: the cores available, at most 8."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - non-Linux
        cores = os.cpu_count() or 1
    return max(1, min(cores, 8))


class _Block:
    """Coefficients ``(M_k, D_k, K_k)`` of one harmonic ``k`` with a shared apply."""

    def __init__(self, M: Any, D: Any, K: Any) -> None:
        self.M, self.D, self.K = M, D, K

    def apply(self, X: np.ndarray, s: np.ndarray) -> np.ndarray:
        """``A_k(n) x_n`` for the columns ``x_n`` of ``X`` (shape (n_dof, b)), ``s = i n w1``."""
        out = np.zeros(X.shape, dtype=complex)
        if self.K is not None:
            out += self.K @ X
        if self.D is not None:
            out += self.D @ (X * s)
        if self.M is not None:
            out += self.M @ (X * (s * s))
        return out


class HarmonicBalance:
    """Harmonic-balance operator; stores and solves only the harmonics ``n >= 0``.

    Parameters
    ----------
    system
        The periodic system.
    harmonics
        The symmetric harmonic set ``H``.
    workers
        Threads for the per-harmonic factorizations and solves.
    """

    def __init__(
        self, system: PeriodicSystem, harmonics: HarmonicSet, *, workers: int | None = None
    ) -> None:
        self.system = system
        self.harmonics = harmonics
        self.full = harmonics.indices
        self.pos = harmonics.nonnegative
        self.n_dof = system.n
        self.w1 = system.omega
        self.workers = default_workers() if workers is None else max(1, int(workers))
        self.sparse = system.is_sparse
        self._where = {int(n): i for i, n in enumerate(self.pos)}
        self._weights = np.where(self.pos == 0, 1.0, 2.0)
        self._factors: list[Callable[[np.ndarray], np.ndarray]] | None = None
        self._blocks = {k: self._block(k) for k in [0, *system.coefficient_harmonics]}
        self._coupling = self._coupling_maps()
        self.rhs = np.zeros((self.pos.size, self.n_dof), dtype=complex)
        for i, n in enumerate(self.pos):
            if int(n) in system.f:
                self.rhs[i] = system.f[int(n)]
        self.rhs_norm = self.norm(self.rhs)

    # ------------------------------------------------------------------ structure
    def _block(self, k: int) -> _Block:
        def get(table: dict) -> Any:
            x = table.get(k)
            if x is None:
                return None
            return sp.csr_array(x) if self.sparse else np.asarray(x)

        s = self.system
        return _Block(get(s.M), get(s.D), get(s.K))

    def _coupling_maps(self) -> list[tuple[_Block, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
        """For each ``k != 0``: rows ``m >= 0`` and columns ``n = m - k in H``."""
        maps = []
        in_h = set(int(n) for n in self.full)
        for k, block in self._blocks.items():
            if k == 0:
                continue
            rows, src, neg, nvals = [], [], [], []
            for i, m in enumerate(self.pos):
                n = int(m) - k
                if n in in_h:
                    rows.append(i)
                    src.append(self._where[abs(n)])
                    neg.append(n < 0)
                    nvals.append(n)
            if rows:
                maps.append(
                    (
                        block,
                        np.array(rows),
                        np.array(src),
                        np.array(neg, dtype=bool),
                        1j * self.w1 * np.array(nvals, dtype=float),
                    )
                )
        return maps

    @property
    def coupling_harmonics(self) -> list[int]:
        """The nonzero coefficient harmonics that couple members of ``H``."""
        return [k for k in self._blocks if k != 0]

    # ------------------------------------------------------------------ vectors
    def norm(self, Q: np.ndarray) -> float:
        """2-norm of the full (both-sided) vector from its half ``n >= 0``."""
        return float(np.sqrt(np.sum(self._weights * np.sum(np.abs(Q) ** 2, axis=1))))

    def expand(self, Q: np.ndarray) -> np.ndarray:
        """Full coefficients over ``H`` (shape (|H|, n_dof)) from the half ``n >= 0``."""
        out = np.empty((self.full.size, self.n_dof), dtype=complex)
        for j, n in enumerate(self.full):
            v = Q[self._where[abs(int(n))]]
            out[j] = v if n >= 0 else np.conj(v)
        return out

    # ------------------------------------------------------------------ operators
    def A0_matrix(self, n: int) -> Any:
        """``A0(n) = -(n w1)^2 M_0 + i n w1 D_0 + K_0`` (sparse CSC or dense)."""
        b = self._blocks[0]
        s = 1j * n * self.w1
        terms = [(b.K, 1.0), (b.D, s), (b.M, s * s)]
        if self.sparse:
            out = sp.csc_array((self.n_dof, self.n_dof), dtype=complex if n else float)
            for x, c in terms:
                if x is not None:
                    out = out + (x * c if n else x * c.real)
            return sp.csc_array(out)
        acc = np.zeros((self.n_dof, self.n_dof), dtype=complex if n else float)
        for x, c in terms:
            if x is not None:
                acc = acc + (x * c if n else x * c.real)
        return acc

    def apply_A0(self, Q: np.ndarray) -> np.ndarray:
        """``A0 q`` by matrix products (not through the factors)."""
        s = 1j * self.w1 * self.pos.astype(float)
        return self._blocks[0].apply(Q.T, s).T

    def apply_dA(self, Q: np.ndarray) -> np.ndarray:
        """``dA q`` on rows ``m >= 0`` as a sparse convolution over harmonic indices."""
        out = np.zeros_like(Q, dtype=complex)
        for block, rows, src, neg, s in self._coupling:
            X = Q[src]
            if neg.any():
                X[neg] = np.conj(X[neg])
            out[rows] += block.apply(X.T, s).T
        return out

    def apply(self, Q: np.ndarray) -> np.ndarray:
        """``A q = A0 q + dA q``."""
        return self.apply_A0(Q) + self.apply_dA(Q)

    def relative_residual(self, Q: np.ndarray) -> float:
        """``||f - A q|| / ||f||`` over the full harmonic set (independent of any solver)."""
        r = self.norm(self.rhs - self.apply(Q))
        return r / self.rhs_norm if self.rhs_norm > 0 else r

    # ------------------------------------------------------------------ factors
    def _factor(self, n: int) -> Callable[[np.ndarray], np.ndarray]:
        A = self.A0_matrix(n)
        if self.sparse:
            try:
                lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A")
            except RuntimeError as exc:
                raise SingularBlockError(n, str(exc)) from None
            diag = np.abs(np.concatenate([lu.U.diagonal()]))
            if diag.size and diag.min() <= 1e3 * np.finfo(float).eps * diag.max():
                raise SingularBlockError(n, "pivot below round-off")
            if np.isrealobj(A):

                def solve_real(r: np.ndarray, lu: Any = lu) -> np.ndarray:
                    both = lu.solve(np.column_stack([r.real, r.imag]))
                    return both[:, 0] + 1j * both[:, 1]

                return solve_real
            def solve_complex(r: np.ndarray, lu: Any = lu) -> np.ndarray:
                return np.asarray(lu.solve(r.astype(complex)))

            return solve_complex
        lu_piv = sla.lu_factor(A, check_finite=False)
        d = np.abs(np.diag(lu_piv[0]))
        if d.min() <= 1e3 * np.finfo(float).eps * d.max():
            raise SingularBlockError(n, "pivot below round-off")
        def solve_dense(r: np.ndarray, f: Any = lu_piv) -> np.ndarray:
            return np.asarray(sla.lu_solve(f, r.astype(complex), check_finite=False))

        return solve_dense

    def factorize(self) -> None:
        """Factorize ``A0(n)`` for every ``n >= 0`` (once; threads over harmonics)."""
        if self._factors is not None:
            return
        ns = [int(n) for n in self.pos]
        if self.workers > 1 and len(ns) > 1:
            with ThreadPoolExecutor(self.workers) as pool:
                self._factors = list(pool.map(self._factor, ns))
        else:
            self._factors = [self._factor(n) for n in ns]
        log.debug("factorized %d blocks of size %d", len(ns), self.n_dof)

    def solve_A0(self, R: np.ndarray) -> np.ndarray:
        """``A0^-1 r`` for every harmonic ``n >= 0`` (rows of ``R``)."""
        self.factorize()
        assert self._factors is not None
        factors = self._factors
        out = np.empty_like(R, dtype=complex)

        def run(chunk: Sequence[int]) -> None:
            for i in chunk:
                out[i] = factors[i](R[i])

        idx = list(range(len(factors)))
        if self.workers > 1 and len(idx) > 1:
            chunks = [idx[j :: self.workers] for j in range(self.workers)]
            with ThreadPoolExecutor(self.workers) as pool:
                list(pool.map(run, chunks))
        else:
            run(idx)
        return out

    # ------------------------------------------------------------------ coupled
    def coupled_matrix(self) -> sp.csc_array:
        """The assembled block-sparse coupled matrix over the full set ``H`` (for ``direct``)."""
        nd = self.n_dof
        pos_of = {int(n): j for j, n in enumerate(self.full)}
        rows_all, cols_all, vals_all = [], [], []
        for k, block in self._blocks.items():
            parts = [(x, c) for x, c in ((block.K, 0), (block.D, 1), (block.M, 2)) if x is not None]
            coo = [
                sp.coo_array(x) if self.sparse else sp.coo_array(np.asarray(x)) for x, _ in parts
            ]
            union = abs(coo[0]).astype(float)
            for extra in coo[1:]:
                union = union + abs(extra).astype(float)
            pattern = sp.coo_array(union)  # union sparsity pattern of K_k, D_k, M_k
            pattern.sum_duplicates()
            r, c = pattern.row, pattern.col
            vals = np.zeros((3, r.size), dtype=complex)
            for (x, power), _ in zip(parts, coo, strict=True):
                dense = x[r, c] if self.sparse else np.asarray(x)[r, c]
                vals[power] = np.asarray(dense).ravel()
            ns, ms = [], []
            for n in self.full:
                m = int(n) + k
                if m in pos_of:
                    ns.append(int(n))
                    ms.append(pos_of[m])
            if not ns:
                continue
            nv = np.array(ns, dtype=float)
            s = 1j * self.w1 * nv
            block_vals = vals[0][None, :] + s[:, None] * vals[1][None, :]
            block_vals = block_vals + (s * s)[:, None] * vals[2][None, :]
            col0 = np.array([pos_of[n] for n in ns]) * nd
            row0 = np.array(ms) * nd
            rows_all.append((row0[:, None] + r[None, :]).ravel())
            cols_all.append((col0[:, None] + c[None, :]).ravel())
            vals_all.append(block_vals.ravel())
        size = self.full.size * nd
        A = sp.coo_array(
            (np.concatenate(vals_all), (np.concatenate(rows_all), np.concatenate(cols_all))),
            shape=(size, size),
        )
        return sp.csc_array(A)

    def full_rhs(self) -> np.ndarray:
        """The load over the full set ``H``, shape (|H|, n_dof)."""
        return self.expand(self.rhs)

    def half(self, Qfull: np.ndarray) -> np.ndarray:
        """The half ``n >= 0`` of full coefficients over ``H``."""
        idx = np.searchsorted(self.full, self.pos)
        return np.asarray(Qfull[idx])
