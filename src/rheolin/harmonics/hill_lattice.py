"""The Hill problem on a harmonic lattice, in second-order form.

With ``q(t) = exp(lambda t) sum_{h in H} q_h exp(i h w1 t)`` the homogeneous system becomes
the quadratic eigenproblem ``Q(lambda) q = 0``,

    Q(lambda)_{mn} = K_{m-n} + s_n D_{m-n} + s_n^2 M_{m-n},   s_n = lambda + i n w1,

over the harmonics ``m, n`` of a lattice (:mod:`rheolin.harmonics.lattice`). Its first-order form is
the Hill pencil of :func:`~rheolin.harmonics.hill_pencil`; a shift-invert step of that pencil needs
only one solve with ``Q(sigma)``, of half the size (docs/stability.md). Every matrix here is
assembled from the block patterns once; a new shift costs one vector operation on the values.
Nothing is quadratic in the lattice size.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from ..system.periodic import PeriodicSystem
from .blocks import Block, Patterns, coefficient_blocks

__all__ = ["LatticeHill"]


#: Entry patterns of :class:`_Coupling`, by harmonics and block patterns (a sweep's speeds share
#: them).
_PATTERNS = Patterns(8)


class _Coupling:
    """Entries ``X_{r-c}`` of K, D, M between row harmonics and column harmonics.

    ``rows``/``cols`` are global indices (harmonic position x n + DOF); ``col_h`` the column
    harmonic of each entry (its ``s_n``); ``K, D, M`` the values. Stored in CSC order.
    """

    def __init__(
        self,
        blocks: dict[int, Block],
        row_h: np.ndarray,
        col_h: np.ndarray,
        n: int,
        skip_zero: bool = False,
    ) -> None:
        self._iwh: tuple[float, np.ndarray] | None = None
        key = (
            row_h.tobytes(),
            col_h.tobytes(),
            n,
            skip_zero,
            tuple((k, b.pattern_key) for k, b in blocks.items()),
        )
        vals: list[np.ndarray] = []
        for k, block in blocks.items():
            if skip_zero and k == 0:
                continue
            target = col_h + k
            pos = np.minimum(np.searchsorted(row_h, target), row_h.size - 1)
            j = np.flatnonzero(row_h[pos] == target)
            if j.size:
                vals.append(np.tile(block.entries()[2], (1, j.size)))
        self.shape = (row_h.size * n, col_h.size * n)
        if not vals:
            self.rows = self.cols = np.zeros(0, dtype=np.int64)
            self.col_h = np.zeros(0)
            self.K = self.D = self.M = np.zeros(0, dtype=complex)
            self.indptr = np.zeros(self.shape[1] + 1, dtype=np.int64)
            return
        # the pattern depends on the harmonics and the blocks' patterns only: a sweep's
        # next speed reuses it (the sort is most of the cost) and gathers its values
        pattern = _PATTERNS.get(key)
        if pattern is None:
            pattern = self._pattern(blocks, row_h, col_h, n, skip_zero)
            _PATTERNS.put(key, pattern)
        self.rows, self.cols, self.col_h, self.indptr, order = pattern
        v = np.concatenate(vals, axis=1)[:, order]
        self.K, self.D, self.M = v[0], v[1], v[2]

    def _pattern(
        self,
        blocks: dict[int, Block],
        row_h: np.ndarray,
        col_h: np.ndarray,
        n: int,
        skip_zero: bool,
    ) -> tuple[np.ndarray, ...]:
        """``(rows, cols, col_h, indptr, order)``: CSC order of the entries, which are
        listed block by block (``order`` sorts the values listed so)."""
        rows, cols, hs = [], [], []
        for k, block in blocks.items():
            if skip_zero and k == 0:
                continue
            # column harmonic c couples to row harmonic c + k
            target = col_h + k
            pos = np.searchsorted(row_h, target)
            pos = np.minimum(pos, row_h.size - 1)
            ok = row_h[pos] == target
            if not ok.any():
                continue
            j = np.flatnonzero(ok)
            i = pos[ok]
            br, bc, _ = block.entries()
            rows.append((i[:, None] * n + br[None, :]).ravel())
            cols.append((j[:, None] * n + bc[None, :]).ravel())
            hs.append(np.repeat(col_h[j], br.size))
        r, c = np.concatenate(rows), np.concatenate(cols)
        order = np.lexsort((r, c))
        rr, cc = r[order].astype(np.int64), c[order].astype(np.int64)
        ch = np.concatenate(hs)[order].astype(float)
        indptr = np.searchsorted(cc, np.arange(self.shape[1] + 1)).astype(np.int64)
        for arr in (rr, cc, ch, indptr, order):
            arr.setflags(write=False)
        return rr, cc, ch, indptr, order

    @property
    def nnz(self) -> int:
        return int(self.rows.size)

    def matrix(self, data: np.ndarray) -> sp.csc_array:
        return sp.csc_array((data, self.rows, self.indptr), shape=self.shape)

    def s(self, lam: complex, w: float) -> np.ndarray:
        # i w h per entry is the same for every shift: made once per frequency
        if self._iwh is None or self._iwh[0] != w:
            self._iwh = (w, 1j * w * self.col_h)
        return lam + self._iwh[1]

    def Q(self, lam: complex, w: float) -> sp.csc_array:
        """``K + s D + s^2 M`` with ``s = lam + i w h_col``."""
        s = self.s(lam, w)
        return self.matrix(self.K + s * (self.D + s * self.M))

    def P(self, lam: complex, w: float) -> sp.csc_array:
        """``D + s M``."""
        return self.matrix(self.D + self.s(lam, w) * self.M)

    def dQ(self, lam: complex, w: float) -> sp.csc_array:
        """``dQ / dlambda = D + 2 s M``."""
        return self.matrix(self.D + 2.0 * self.s(lam, w) * self.M)

    def Mconv(self) -> sp.csc_array:
        return self.matrix(self.M)


class LatticeHill:
    """Second-order Hill operator of ``system`` on the harmonics ``H`` (sorted, symmetric).

    Parameters
    ----------
    system
        The periodic system.
    H
        Sorted harmonic indices (a lattice).

    Examples
    --------
    Mathieu's equation ``y'' + (1 - 0.4 cos 2t) y = 0`` (``w1 = 2``) on ``-1..1``:

    >>> import numpy as np, rheolin as rl
    >>> s = rl.PeriodicSystem(2.0, M={0: np.eye(1)}, K={0: np.eye(1), 1: -0.2 * np.eye(1)})
    >>> hill = LatticeHill(s, np.array([-1, 0, 1]))
    >>> hill.Q(0.0).toarray().real
    array([[-3. , -0.2,  0. ],
           [-0.2,  1. , -0.2],
           [ 0. , -0.2, -3. ]])
    """

    def __init__(self, system: PeriodicSystem, H: np.ndarray) -> None:
        self.system = system
        self.H = np.asarray(H, dtype=np.int64)
        self.n = system.n
        self.w = system.omega
        self.blocks = coefficient_blocks(system)
        self.inner = _Coupling(self.blocks, self.H, self.H, self.n)
        self._outer: tuple[np.ndarray, _Coupling, _Coupling] | None = None
        self._pardiso: tuple[tuple[int, int, int], Any] | None = None
        self._ordered: Any = None  # SuperLU factors in one ordering (shift_invert.PatternLU)
        self.size = self.H.size * self.n

    # ------------------------------------------------------------------ inside
    def Q(self, lam: complex) -> sp.csc_array:
        """``Q(lambda)`` on the lattice (``n |H|`` square, CSC)."""
        return self.inner.Q(lam, self.w)

    def s(self, lam: complex) -> np.ndarray:
        """``s_h = lambda + i h w1`` expanded per DOF (length ``n |H|``)."""
        return np.repeat(lam + 1j * self.w * self.H.astype(float), self.n)

    # ------------------------------------------------------------------ outside
    def outer(self) -> tuple[np.ndarray, _Coupling, _Coupling]:
        """Harmonics one coefficient step outside the lattice, and the couplings
        ``Q_OI`` (outside rows, lattice columns) and ``Q_IO`` (lattice rows, outside columns)."""
        if self._outer is None:
            ks = np.array([k for k in self.blocks if k != 0], dtype=np.int64)
            if ks.size == 0:
                O = np.zeros(0, dtype=np.int64)
            else:
                cand = np.unique((self.H[:, None] + ks[None, :]).ravel())
                pos = np.minimum(np.searchsorted(self.H, cand), self.H.size - 1)
                O = cand[self.H[pos] != cand]
            oi = _Coupling(self.blocks, O, self.H, self.n, skip_zero=True)
            io = _Coupling(self.blocks, self.H, O, self.n, skip_zero=True)
            self._outer = (O, oi, io)
        return self._outer

    def pardiso_analysis(self, Q: sp.csc_array, *, slots: int, refinement: int) -> Any:
        """The MKL PARDISO analysis (:class:`~rheolin.linalg.direct.pardiso.PardisoBackend`)
        of the pattern of ``Q`` (CSC with sorted indices; this lattice's ``Q`` at every shift
        shares one), made on first use and kept here. Kept per lattice, not across calls:
        MKL PARDISO crashes when its thread count changes between the analysis and a
        factorization (``threadpool_limits`` entered anew by the next call)."""
        from ..linalg.direct import csc_pattern_key
        from ..linalg.direct.pardiso import PardisoBackend

        key = csc_pattern_key(Q.indptr, Q.indices)
        if self._pardiso is None or self._pardiso[0] != key:
            backend = PardisoBackend(
                Q.indptr.astype(np.int64),
                Q.indices.astype(np.int64),
                True,
                slots=slots,
                refinement=refinement,
            )
            self._pardiso = (key, backend)
        return self._pardiso[1]

    def memory_bytes(self, fill: float = 8.0) -> int:
        """Estimate of the memory of one shift: ``Q`` and its LU (``fill`` x its entries)."""
        return int(self.inner.nnz * 16 * (3 + fill) + self.size * 16 * 40)
