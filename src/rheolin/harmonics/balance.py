"""The harmonic-balance operator of a :class:`PeriodicSystem` on a :class:`HarmonicSet`.

Row ``m`` of the coupled system (docs/conventions.md, seed eq. 3)::

    sum_{n in H} A_{m-n}(n) q_n = f_m,   A_k(n) = -(n w1)^2 M_k + i n w1 D_k + K_k

Only the half ``n >= 0`` is stored and solved (``q_{-n} = conj(q_n)`` for a real system).
``A0`` (the block diagonal, ``k = 0``) is factorized once per ``n >= 0``; the time-varying
part ``dA`` is applied as a sparse convolution over harmonic indices, never assembled.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..budget import format_bytes, solve_budget
from ..linalg import BlockInverse, Pencil, SingularBlockError, default_workers, make_inverse
from ..linalg.memory import MIN_RESTART, SolveMemory
from ..linalg.memory import check as check_memory
from ..linalg.store import FactorStore
from ..system.periodic import PeriodicSystem
from .blocks import Block, Patterns, coefficient_blocks
from .sets import HarmonicSet

__all__ = ["HarmonicBalance", "SingularBlockError", "default_workers"]

log = logging.getLogger(__name__)

#: Patterns of :meth:`HarmonicBalance._support_matrices`, by harmonics and block patterns.
_SUPPORT_PATTERNS = Patterns()


class HarmonicBalance:
    """Harmonic-balance operator; stores and solves only the harmonics ``n >= 0``.

    Parameters
    ----------
    system
        The periodic system.
    harmonics
        The symmetric harmonic set ``H``.
    workers
        Threads for the per-harmonic factorizations and solves (one long-lived pool).
    backend
        Inverse of ``A0(n)``: ``"auto"``, ``"lu"``, ``"dense"`` or ``"modal"``
        (:mod:`rheolin.linalg`).
    sparse_backend
        Sparse direct solver of ``lu``: ``"auto"``, ``"pardiso"``, ``"umfpack"`` or
        ``"superlu"`` (:mod:`rheolin.linalg.direct`).
    memory_budget
        Bytes (or ``"8 GB"``) the solve may use; default :func:`rheolin.budget.solve_budget`.
        The estimate (:attr:`memory`) is checked before the load vector is allocated
        (:class:`~rheolin.budget.MemoryBudgetError`), and the factors are held only while
        they fit.
    """

    def __init__(
        self,
        system: PeriodicSystem,
        harmonics: HarmonicSet,
        *,
        workers: int | None = None,
        backend: str = "auto",
        sparse_backend: str = "auto",
        memory_budget: str | int | None = None,
    ) -> None:
        self.system = system
        self.harmonics = harmonics
        self.full = harmonics.indices
        self.pos = harmonics.nonnegative
        self.n_dof = system.n
        self.w1 = system.omega
        self.workers = default_workers() if workers is None else max(1, int(workers))
        self.sparse = system.is_sparse
        self._weights = np.where(self.pos == 0, 1.0, 2.0)
        self.backend = backend
        self.backend_note = ""
        self._inverse: BlockInverse | None = None
        self._last_residual: tuple[np.ndarray, int, np.ndarray] | None = None
        self._support_maps: tuple[Any, sp.csr_array, sp.csr_array] | None = None
        self._norm_bound: float | None = None
        self._blocks = coefficient_blocks(system)
        self.pencil = self._pencil()
        self._coupling = self._coupling_maps()
        self.sparse_backend = sparse_backend
        self.budget = solve_budget(memory_budget)
        self.memory = SolveMemory(self.n_dof, int(self.pos.size), int(self.support[0].size))
        check_memory(self.memory, self.budget)
        self.rhs = np.zeros((self.pos.size, self.n_dof), dtype=complex)
        for i, n in enumerate(self.pos):
            if int(n) in system.f:
                self.rhs[i] = system.f[int(n)]
        self.rhs_norm = self.norm(self.rhs)

    # ------------------------------------------------------------------ structure
    def _pencil(self) -> Pencil:
        """``A0(n)`` on the union pattern of ``K_0, D_0, M_0`` (built once from block 0)."""
        s = self.system
        if not self.sparse:
            return Pencil(s.K.get(0), s.D.get(0), s.M.get(0), self.w1)
        rows, cols, values = self._blocks[0].entries()  # CSC order
        indptr = np.searchsorted(cols, np.arange(self.n_dof + 1))
        return Pencil.from_csc(indptr, rows, values.real, self.w1)  # X_0 is real

    def _coupling_maps(self) -> list[tuple[Block, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
        """For each ``k != 0``: rows ``m >= 0`` and columns ``n = m - k in H``."""
        maps = []
        H = self.full
        for k, block in self._blocks.items():
            if k == 0:
                continue
            n = self.pos - k
            j = np.clip(np.searchsorted(H, n), 0, H.size - 1)
            rows = np.flatnonzero(H[j] == n)
            if rows.size:
                nv = n[rows]
                src = np.searchsorted(self.pos, np.abs(nv))
                maps.append((block, rows, src, nv < 0, 1j * self.w1 * nv.astype(float)))
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
        """``dA`` restricted to ``rows x cols`` as sparse matrices over (harmonic, DOF) pairs.

        Their pattern depends on the harmonics and the blocks' patterns only: it is built once
        and kept (:data:`_SUPPORT_PATTERNS`) for the next speeds of a sweep, which only
        compute the values."""
        key = self._support_key(rows, cols)
        pattern = _SUPPORT_PATTERNS.get(key)
        nr, nc = rows.size, cols.size
        shape = (self.pos.size * nr, self.pos.size * nc)
        values: dict[bool, list[np.ndarray]] = {False: [], True: []}
        index: dict[bool, tuple[list, list]] = {False: ([], []), True: ([], [])}
        for block, hrows, src, neg, s in self._coupling:
            vals = block.values(s)
            if pattern is None:
                br, bc, _ = block.entries()
                r = hrows[:, None] * nr + np.searchsorted(rows, br)[None, :]
                c = src[:, None] * nc + np.searchsorted(cols, bc)[None, :]
            for flag in (False, True):
                pick = neg == flag
                if pick.any():
                    values[flag].append(vals[pick].ravel())
                    if pattern is None:
                        index[flag][0].append(r[pick].ravel())
                        index[flag][1].append(c[pick].ravel())
        if pattern is None:
            pattern = {}
            for flag in (False, True):
                r_list, c_list = index[flag]
                if not r_list:
                    pattern[flag] = None
                    continue
                r, c = np.concatenate(r_list), np.concatenate(c_list)
                order = np.lexsort((c, r))  # CSR order (duplicates kept: they add up)
                indptr = np.zeros(shape[0] + 1, dtype=np.int64)
                np.cumsum(np.bincount(r, minlength=shape[0]), out=indptr[1:])
                pattern[flag] = (order, c[order].astype(np.int64), indptr)
            _SUPPORT_PATTERNS.put(key, pattern)

        def build(flag: bool) -> sp.csr_array:
            got = pattern[flag]
            if got is None:
                return sp.csr_array(shape, dtype=complex)
            order, indices, indptr = got
            data = np.concatenate(values[flag])[order]
            return sp.csr_array((data, indices, indptr), shape=shape)

        return build(False), build(True)

    def _support_key(self, rows: np.ndarray, cols: np.ndarray) -> tuple[Any, ...]:
        """What the support matrices' pattern depends on."""
        parts: list[Any] = [self.pos.tobytes(), self.full.tobytes(), rows.tobytes(), cols.tobytes()]
        parts.extend((k, b.pattern_key) for k, b in self._blocks.items() if k != 0)
        return tuple(parts)

    def wide_harmonics(self, limit: int) -> list[int]:
        """Coefficient harmonics ``k != 0`` whose block touches more than ``limit`` DOFs (an
        asymmetric shaft, not a gear mesh or a single disk)."""
        return sorted(
            k for k, b in self._blocks.items() if k != 0 and max(b.rows.size, b.cols.size) > limit
        )

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
        out = Q[np.searchsorted(self.pos, np.abs(self.full))].astype(complex)
        neg = self.full < 0
        out[neg] = np.conj(out[neg])
        return out

    # ------------------------------------------------------------------ operators
    def A0_matrix(self, n: int) -> Any:
        """``A0(n) = -(n w1)^2 M_0 + i n w1 D_0 + K_0`` (sparse CSC or dense)."""
        return self.pencil.matrix(n)

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
        """``dA q`` on rows ``m >= 0`` as a sparse convolution over harmonic indices.

        Through the support matrices of :meth:`apply_dA_support` when a solver has built them
        for the whole support (one sparse product), else block by block.
        """
        rows, cols = self.support
        if self._support_maps is not None and self._support_maps[0] == (
            rows.tobytes(),
            cols.tobytes(),
        ):
            out = np.zeros_like(Q, dtype=complex)
            out[:, rows] = self.apply_dA_support(Q[:, cols], rows, cols)
            return out
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

    def residual(self, Q: np.ndarray) -> np.ndarray:
        """``f - A q`` on the half ``n >= 0`` (the last one is kept: a solver that refines
        against it and the final check of :func:`rheolin.solve` share one product)."""
        last = self._last_residual
        if last is not None and last[0] is Q and last[1] == Q.tobytes().__hash__():
            return last[2]
        R = self.rhs - self.apply(Q)
        self._last_residual = (Q, Q.tobytes().__hash__(), R)
        return R

    def relative_residual(self, Q: np.ndarray) -> float:
        """``||f - A q|| / ||f||`` over the full harmonic set (independent of any solver)."""
        r = self.norm(self.residual(Q))
        return r / self.rhs_norm if self.rhs_norm > 0 else r

    @property
    def norm_bound(self) -> float:
        """An upper bound of ``||A||_2`` of the coupled harmonic-balance operator:
        ``max_n sum_k ((n w1)^2 ||M_k|| + |n w1| ||D_k|| + ||K_k||)`` over the harmonic set
        and the coefficient harmonics, each ``||X||_2 <= sqrt(||X||_1 ||X||_inf)``."""
        if self._norm_bound is None:
            s = self.system

            def bound(x: Any) -> float:
                a = abs(x)
                one = float(np.max(np.asarray(a.sum(axis=0)), initial=0.0))
                inf = float(np.max(np.asarray(a.sum(axis=1)), initial=0.0))
                return float(np.sqrt(one * inf))

            m = sum(bound(x) for x in s.M.values())
            d = sum(bound(x) for x in s.D.values())
            k = sum(bound(x) for x in s.K.values())
            w = float(np.max(np.abs(self.full))) * s.omega
            self._norm_bound = w * w * m + w * d + k
        return float(self._norm_bound)

    def backward_error(self, Q: np.ndarray) -> float:
        """Normwise backward error ``||f - A q|| / (||A|| ||q|| + ||f||)`` (2-norms over the
        full harmonic set, ``||A||`` bounded above by :attr:`norm_bound`): the smallest
        relative change of ``A`` and ``f`` of which ``q`` is the exact solution. Unlike
        :meth:`relative_residual` it does not grow with the stiffness scale of the model
        (stiff ties of 1e13 N/m), and it is never larger than it."""
        r = self.norm(self.residual(Q))
        scale = self.norm_bound * self.norm(Q) + self.rhs_norm
        return r / scale if scale > 0 else r

    # ------------------------------------------------------------------ factors
    @property
    def inverse(self) -> BlockInverse:
        """``A0(n)^-1`` for every ``n >= 0`` (made on first use by :attr:`backend`)."""
        if self._inverse is None:
            # the factors first, beside the shortest GMRES basis: a factor not held is made
            # again at every iteration, a shorter restart costs iterations only where more
            # are needed than it holds (the restart is fitted to what the factors leave)
            shortest = dataclasses.replace(self.memory, restart=MIN_RESTART)
            spare = self.budget - shortest.vectors - shortest.krylov
            self._inverse, self.backend_note = make_inverse(
                self.pencil,
                self.pos,
                self.backend,
                self.workers,
                self.sparse_backend,
                max(spare, 0),
            )
            decomposition = getattr(self._inverse, "decomposition", None)
            if decomposition is not None:  # the system's time-averaged modes, for floquet
                self.system.keep("averaged_decomposition", decomposition)
            store = self.factor_store
            if store is not None:
                self.memory.factor_bytes = store.factor_bytes
                self.memory.factors_held = store.factors_alive
                check_memory(self.memory, self.budget)
                if store.on_demand:
                    note = (
                        f"factors of {store.capacity} of {int(np.count_nonzero(self.pos))} "
                        f"harmonics held within the memory budget "
                        f"({format_bytes(self.budget)}); the others refactorized on demand"
                    )
                    self.backend_note = f"{self.backend_note}; {note}".lstrip("; ")
            log.debug("A0 inverse: %s %s", self._inverse.name, self.backend_note)
        return self._inverse

    @property
    def factor_store(self) -> FactorStore | None:
        """The sparse factors of ``A0(n)`` once :attr:`inverse` is made and keeps them in a
        :class:`~rheolin.linalg.store.FactorStore`; None otherwise (this makes nothing)."""
        return getattr(self._inverse, "store", None)

    def factorize(self) -> None:
        """Make the inverse of ``A0(n)`` for every ``n >= 0`` now (once)."""
        _ = self.inverse

    def solve_A0(self, R: np.ndarray) -> np.ndarray:
        """``A0^-1 r`` for every harmonic ``n >= 0`` (rows of ``R``)."""
        return self.inverse.solve(R)

    def restricted_solver(
        self, rows: np.ndarray, cols: np.ndarray
    ) -> Callable[[np.ndarray], np.ndarray]:
        """``Z -> (A0(n)^-1[rows, cols] z_n)_n`` over the harmonics ``n >= 0``."""
        return self.inverse.restricted(rows, cols)

    def restricted_inverse(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """``G_n = A0(n)^-1[rows, cols]`` for every ``n >= 0``, shape (|H+|, |rows|, |cols|)."""
        apply = self.restricted_solver(rows, cols)
        eye = np.eye(cols.size, dtype=complex)
        return np.stack([apply(np.broadcast_to(e, (self.pos.size, cols.size))) for e in eye], -1)

    # ------------------------------------------------------------------ coupled
    def coupled_entries(self) -> int:
        """Entries :meth:`coupled_matrix` stores (duplicates counted), from the blocks'
        patterns and the harmonic pairs they couple, without assembling it."""
        full = np.asarray(self.full, dtype=np.int64)
        total = 0
        for k, block in self._blocks.items():
            r, _, _ = block.entries()
            total += int(np.isin(full + int(k), full).sum()) * int(r.size)
        return total

    def coupled_matrix(self, harmonics: Iterable[int] | None = None) -> sp.csc_array:
        """The assembled block-sparse coupled matrix over the full set ``H`` (for ``direct``);
        with ``harmonics``, only the coefficient harmonics ``k`` listed (0 is always kept):
        a preconditioner that holds part of the coupling exactly."""
        nd = self.n_dof
        pos_of = {int(n): j for j, n in enumerate(self.full)}
        rows_all, cols_all, vals_all = [], [], []
        wanted = None if harmonics is None else {0, *(int(k) for k in harmonics)}
        for k, block in self._blocks.items():
            if wanted is not None and k not in wanted:
                continue
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
