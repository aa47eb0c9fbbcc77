"""The harmonic-balance operator of a :class:`PeriodicSystem` on a :class:`HarmonicSet`.

Row ``m`` of the coupled system (DESIGN.md §2, seed eq. 3)::

    sum_{n in H} A_{m-n}(n) q_n = f_m,   A_k(n) = -(n w1)^2 M_k + i n w1 D_k + K_k

Only the half ``n >= 0`` is stored and solved (``q_{-n} = conj(q_n)`` for a real system).
``A0`` (the block diagonal, ``k = 0``) is factorized once per ``n >= 0``; the time-varying
part ``dA`` is applied as a sparse convolution over harmonic indices, never assembled.
"""

from __future__ import annotations

import functools
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


def default_workers() -> int:
    """Threads for per-harmonic work: the cores available, at most 8."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - non-Linux
        cores = os.cpu_count() or 1
    return max(1, min(cores, 8))


@functools.lru_cache(maxsize=8)
def _probe_vector(size: int) -> np.ndarray:
    """A fixed random right-hand side that checks each factorization (made once per size)."""
    b = np.random.default_rng(size).standard_normal(size)
    b.setflags(write=False)
    return b


class _Block:
    """Coefficients ``(M_k, D_k, K_k)`` of one harmonic ``k``, compressed to their support.

    Time-varying parts are local (a gear mesh touches two nodes, an asymmetric body its own
    DOFs), so each block keeps only its nonzero rows and columns: applying it reads and
    writes ``b x support`` entries, not ``b x n``.
    """

    def __init__(self, M: Any, D: Any, K: Any, n: int, sparse: bool) -> None:
        present = [x for x in (M, D, K) if x is not None]
        rows = np.zeros(n, dtype=bool)
        cols = np.zeros(n, dtype=bool)
        for x in present:
            nz = sp.coo_array(x) if sparse else sp.coo_array(np.asarray(x))
            rows[nz.row] = True
            cols[nz.col] = True
        self.full = bool(rows.sum() > n // 2 or cols.sum() > n // 2)
        self.rows = np.arange(n) if self.full else np.flatnonzero(rows)
        self.cols = np.arange(n) if self.full else np.flatnonzero(cols)

        def compress(x: Any) -> Any:
            if x is None:
                return None
            if self.full:
                return x
            sub = (sp.csr_array(x) if sparse else np.asarray(x))[self.rows][:, self.cols]
            return sp.csr_array(sub) if sparse else np.asarray(sub)

        self.M, self.D, self.K = compress(M), compress(D), compress(K)
        self.n = n
        self._entries: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def entries(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The union pattern of ``K, D, M`` in global DOF indices, sorted by (column, row)
        (CSC order), and the values on it: ``rows, cols, values`` with ``values`` of shape
        ``(3, nnz)`` holding ``K, D, M`` (zero where one is absent). Built once."""
        if self._entries is None:
            coos = [None if x is None else sp.coo_array(x) for x in (self.K, self.D, self.M)]
            keys = [
                None if x is None else self.cols[x.col].astype(np.int64) * self.n + self.rows[x.row]
                for x in coos
            ]
            union = np.unique(np.concatenate([k for k in keys if k is not None]))
            values = np.zeros((3, union.size), dtype=complex)
            for j, (x, k) in enumerate(zip(coos, keys, strict=True)):
                if x is not None and k is not None:
                    np.add.at(values[j], np.searchsorted(union, k), x.data)
            self._entries = (union % self.n, union // self.n, values)
        return self._entries

    def values(self, s: np.ndarray) -> np.ndarray:
        """``K + s D + s^2 M`` on :meth:`entries`' pattern, one row per ``s``."""
        _, _, (K, D, M) = self.entries()
        return K[None, :] + s[:, None] * D[None, :] + (s * s)[:, None] * M[None, :]

    def apply(self, Xc: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Rows ``self.rows`` of ``A_k(n) x_n``; ``Xc`` holds columns ``self.cols`` of ``x_n``.

        One harmonic per row of ``Xc`` (shape ``(b, len(self.cols))``), ``s = i n w1`` per
        row. Returns shape ``(b, len(self.rows))``.
        """
        out = np.zeros((Xc.shape[0], self.rows.size), dtype=complex)
        if self.K is not None:
            out += (self.K @ Xc.T).T
        if self.D is not None:
            out += (self.D @ (Xc * s[:, None]).T).T
        if self.M is not None:
            out += (self.M @ (Xc * (s * s)[:, None]).T).T
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
        self._pattern: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._support_maps: tuple[Any, sp.csr_array, sp.csr_array] | None = None
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
        return _Block(get(s.M), get(s.D), get(s.K), self.n_dof, self.sparse)

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
    def support(self) -> tuple[np.ndarray, np.ndarray]:
        """Rows and columns (DOF indices) touched by the time-varying part ``dA``."""
        rows = [b.rows for k, b in self._blocks.items() if k != 0]
        cols = [b.cols for k, b in self._blocks.items() if k != 0]
        if not rows:
            return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
        return np.unique(np.concatenate(rows)), np.unique(np.concatenate(cols))

    def apply_dA_support(self, Qc: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """``dA q`` on rows ``rows`` from ``Qc = q[:, cols]`` (both within :attr:`support`).

        Applied as two assembled sparse matrices over (harmonic, DOF) pairs, one for the
        sources ``n >= 0`` and one for the conjugated sources ``n < 0`` (built on first use
        for these ``rows, cols``): one sparse product instead of a Python loop over the
        coefficient harmonics in every Krylov iteration.
        """
        key = (rows.tobytes(), cols.tobytes())
        if self._support_maps is None or self._support_maps[0] != key:
            self._support_maps = (key, *self._support_matrices(rows, cols))
        _, direct, conjugated = self._support_maps
        x = np.ascontiguousarray(Qc).ravel()
        out = direct @ x
        if conjugated.nnz:
            out = out + conjugated @ np.conj(x)
        return np.asarray(out).reshape(self.pos.size, rows.size)

    def _support_matrices(
        self, rows: np.ndarray, cols: np.ndarray
    ) -> tuple[sp.csr_array, sp.csr_array]:
        """``dA`` restricted to ``rows x cols`` as sparse matrices over (harmonic, DOF) pairs."""
        nr, nc = rows.size, cols.size
        parts: dict[bool, tuple[list, list, list]] = {False: ([], [], []), True: ([], [], [])}
        for block, hrows, src, neg, s in self._coupling:
            br, bc, _ = block.entries()
            r = hrows[:, None] * nr + np.searchsorted(rows, br)[None, :]
            c = src[:, None] * nc + np.searchsorted(cols, bc)[None, :]
            vals = block.values(s)
            for flag in (False, True):
                pick = neg == flag
                if pick.any():
                    parts[flag][0].append(r[pick].ravel())
                    parts[flag][1].append(c[pick].ravel())
                    parts[flag][2].append(vals[pick].ravel())
        shape = (self.pos.size * nr, self.pos.size * nc)

        def build(flag: bool) -> sp.csr_array:
            r, c, v = parts[flag]
            if not r:
                return sp.csr_array(shape, dtype=complex)
            coo = sp.coo_array(
                (np.concatenate(v), (np.concatenate(r), np.concatenate(c))), shape=shape
            )
            return sp.csr_array(coo)

        return build(False), build(True)

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
    def _A0_pattern(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The union CSC pattern of ``K_0, D_0, M_0`` and their values on it (rows K, D, M).

        Built once: every ``A0(n)`` is then one vector operation on these values instead of
        three sparse additions (which cost more than the factorization of a 126-DOF block).
        """
        if self._pattern is None:
            rows, cols, values = self._blocks[0].entries()
            indptr = np.searchsorted(cols, np.arange(self.n_dof + 1)).astype(np.int64)
            self._pattern = (indptr, rows.astype(np.int64), values.real)  # X_0 is real
        return self._pattern

    def A0_matrix(self, n: int) -> Any:
        """``A0(n) = -(n w1)^2 M_0 + i n w1 D_0 + K_0`` (sparse CSC or dense)."""
        s = 1j * n * self.w1
        if self.sparse:
            indptr, indices, (k0, d0, m0) = self._A0_pattern()
            data = k0 + s * d0 + (s * s) * m0 if n else k0.copy()
            return sp.csc_array((data, indices.copy(), indptr.copy()), shape=(self.n_dof,) * 2)
        b = self._blocks[0]
        terms = [(b.K, 1.0), (b.D, s), (b.M, s * s)]
        acc = np.zeros((self.n_dof, self.n_dof), dtype=complex if n else float)
        for x, c in terms:
            if x is not None:
                acc = acc + (x * c if n else x * c.real)
        return acc

    def apply_A0(self, Q: np.ndarray) -> np.ndarray:
        """``A0 q`` by matrix products (not through the factors)."""
        s = 1j * self.w1 * self.pos.astype(float)
        block = self._blocks[0]
        if block.full:
            return block.apply(Q, s)
        out = np.zeros_like(Q, dtype=complex)
        out[:, block.rows] = block.apply(Q[:, block.cols], s)
        return out

    def apply_dA(self, Q: np.ndarray) -> np.ndarray:
        """``dA q`` on rows ``m >= 0`` as a sparse convolution over harmonic indices."""
        out = np.zeros_like(Q, dtype=complex)
        for block, rows, src, neg, s in self._coupling:
            X = Q[src] if block.full else Q[np.ix_(src, block.cols)]
            if neg.any():
                X[neg] = np.conj(X[neg])
            if block.full:
                out[rows] += block.apply(X, s)
            else:
                out[np.ix_(rows, block.rows)] += block.apply(X, s)
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
            lu = self._splu_checked(A, n)
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
        lu_piv = sla.lu_factor(A, check_finite=False)
        d = np.abs(np.diag(lu_piv[0]))
        if d.min() <= 1e3 * np.finfo(float).eps * d.max():
            raise SingularBlockError(n, "pivot below round-off")

        def solve_dense(r: np.ndarray, f: Any = lu_piv) -> np.ndarray:
            return np.asarray(sla.lu_solve(f, r.astype(complex), check_finite=False))

        return solve_dense

    @staticmethod
    def _splu_checked(A: Any, n: int) -> Any:
        """Sparse LU with diagonal-preferring pivoting, checked; partial pivoting if inaccurate."""
        b = _probe_vector(A.shape[0])
        for options in (SPLU_OPTIONS, {"permc_spec": "MMD_AT_PLUS_A"}):
            try:
                lu = spla.splu(A, **options)
            except RuntimeError as exc:
                raise SingularBlockError(n, str(exc)) from None
            diag = np.abs(lu.U.diagonal())
            if diag.size and diag.min() <= 1e3 * np.finfo(float).eps * diag.max():
                raise SingularBlockError(n, "pivot below round-off")
            x = lu.solve(b.astype(A.dtype))
            if np.linalg.norm(A @ x - b) <= 1e-11 * np.linalg.norm(b):
                return lu
            log.debug("A0(%d): threshold pivoting inaccurate; refactorizing", n)
        return lu

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

        self._map_chunks(run, len(factors))
        return out

    def restricted_inverse(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """``G_n = A0(n)^-1[rows, cols]`` for every ``n >= 0``, shape (|H+|, |rows|, |cols|).

        One multi-column solve per harmonic with the unit vectors of ``cols``.
        """
        self.factorize()
        assert self._factors is not None
        factors = self._factors
        E = np.zeros((self.n_dof, cols.size), dtype=complex)
        E[cols, np.arange(cols.size)] = 1.0
        out = np.empty((len(factors), rows.size, cols.size), dtype=complex)

        def run(chunk: Sequence[int]) -> None:
            for i in chunk:
                out[i] = factors[i](E)[rows]

        self._map_chunks(run, len(factors))
        return out

    def _map_chunks(self, run: Callable[[Sequence[int]], None], count: int) -> None:
        idx = list(range(count))
        if self.workers > 1 and count > 1:
            chunks = [idx[j :: self.workers] for j in range(self.workers)]
            with ThreadPoolExecutor(self.workers) as pool:
                list(pool.map(run, chunks))
        else:
            run(idx)

    # ------------------------------------------------------------------ coupled
    def coupled_matrix(self) -> sp.csc_array:
        """The assembled block-sparse coupled matrix over the full set ``H`` (for ``direct``)."""
        nd = self.n_dof
        pos_of = {int(n): j for j, n in enumerate(self.full)}
        rows_all, cols_all, vals_all = [], [], []
        for k, block in self._blocks.items():
            r, c, _ = block.entries()
            ns, ms = [], []
            for n in self.full:
                m = int(n) + k
                if m in pos_of:
                    ns.append(int(n))
                    ms.append(pos_of[m])
            if not ns:
                continue
            block_vals = block.values(1j * self.w1 * np.array(ns, dtype=float))
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
