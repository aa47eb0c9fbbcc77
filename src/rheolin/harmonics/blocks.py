"""Coefficient storage: the blocks ``(M_k, D_k, K_k)`` of a periodic system, compressed to
their support, and a small cache of the entry patterns built from them.

The harmonic-balance operator (:mod:`rheolin.harmonics.balance`), the Hill lattice
(:mod:`rheolin.harmonics.hill_lattice`) and the averaged modes of the stability check all read
a system's coefficients through these blocks.

>>> import numpy as np
>>> from rheolin.system import PeriodicSystem
>>> K1 = np.zeros((3, 3))
>>> K1[1, 2] = 0.5
>>> s = PeriodicSystem(1.0, M={0: np.eye(3)}, K={0: np.eye(3), 1: K1})
>>> blocks = coefficient_blocks(s)
>>> list(blocks)
[0, -1, 1]
>>> blocks[1].rows, blocks[1].cols
(array([1]), array([2]))
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from ..system.periodic import PeriodicSystem

__all__ = ["Block", "Patterns", "coefficient_blocks"]


class Block:
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

        # every entry lies on the support: a sparse block is its entries relabelled (a
        # fancy index of rows, then columns, costs ten times more on a gearbox's blocks)
        at_row = np.full(n, -1, dtype=np.int64)
        at_row[self.rows] = np.arange(self.rows.size)
        at_col = np.full(n, -1, dtype=np.int64)
        at_col[self.cols] = np.arange(self.cols.size)
        shape = (self.rows.size, self.cols.size)

        def compress(x: Any) -> Any:
            if x is None:
                return None
            if self.full:
                return x
            if not sparse:
                return np.asarray(x)[np.ix_(self.rows, self.cols)]
            c = sp.coo_array(x)
            return sp.csr_array((c.data, (at_row[c.row], at_col[c.col])), shape=shape)

        self.M, self.D, self.K = compress(M), compress(D), compress(K)
        self.n = n
        self._entries: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._pattern_key: bytes | None = None

    @property
    def pattern_key(self) -> bytes:
        """The union pattern of :meth:`entries` as bytes (a cache key for the patterns of
        operators assembled from this block; values change with the speed, this does not)."""
        if self._pattern_key is None:
            rows, cols, _ = self.entries()
            self._pattern_key = rows.tobytes() + b"|" + cols.tobytes()
        return self._pattern_key

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


class Patterns:
    """A few recent entry patterns (a sweep reuses one at every speed), at most ``size`` of
    them and ``limit`` bytes in all (a larger one is not kept)."""

    def __init__(self, size: int = 4, limit: int = 256 * 2**20) -> None:
        self.size, self.limit = size, limit
        self._kept: dict[Any, tuple[Any, int]] = {}

    def get(self, key: Any) -> Any:
        got = self._kept.pop(key, None)
        if got is None:
            return None
        self._kept[key] = got  # most recent last
        return got[0]

    def put(self, key: Any, value: Any) -> None:
        size = _nbytes(value)
        self._kept.pop(key, None)
        if size > self.limit:
            return
        self._kept[key] = (value, size)
        while len(self._kept) > self.size or sum(b for _, b in self._kept.values()) > self.limit:
            self._kept.pop(next(iter(self._kept)))


def _nbytes(value: Any) -> int:
    """Bytes of the arrays in a (nested) tuple or dict."""
    if isinstance(value, np.ndarray):
        return int(value.nbytes)
    if isinstance(value, dict):
        return sum(_nbytes(v) for v in value.values())
    if isinstance(value, (tuple, list)):
        return sum(_nbytes(v) for v in value)
    return 0


def coefficient_blocks(system: PeriodicSystem) -> dict[int, Block]:
    """The :class:`Block` of every coefficient harmonic of ``system`` (0 first), built once
    per system and kept on it (:meth:`~rheolin.system.PeriodicSystem.cached`): the solve, the
    stability check and its memory estimate all use them."""
    return dict(system.cached("coefficient_blocks", lambda: _build_blocks(system)))


def _build_blocks(system: PeriodicSystem) -> dict[int, Block]:
    sparse = system.is_sparse

    def get(table: dict, k: int) -> Any:
        x = table.get(k)
        if x is None:
            return None
        return sp.csr_array(x) if sparse else np.asarray(x)

    return {
        k: Block(get(system.M, k), get(system.D, k), get(system.K, k), system.n, sparse)
        for k in [0, *system.coefficient_harmonics]
    }
