"""The time-averaged pencil ``A0(n) = K_0 + s D_0 + s^2 M_0``, ``s = i n w1``
(docs/conventions.md)."""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

__all__ = ["Pencil"]


class Pencil:
    """``A0(n)`` on the union pattern of the real ``K_0, D_0, M_0``.

    Parameters
    ----------
    K, D, M
        The mean coefficients: SciPy sparse or dense arrays (None: zero), all ``n x n``.
    w1
        Base frequency [rad/s].

    Examples
    --------
    >>> import numpy as np
    >>> p = Pencil(np.eye(2), None, np.eye(2), 2.0)
    >>> p.matrix(1)
    array([[-3.+0.j,  0.+0.j],
           [ 0.+0.j, -3.+0.j]])
    >>> p.apply(np.ones((1, 2)), np.array([1]))
    array([[-3.+0.j, -3.+0.j]])
    """

    def __init__(self, K: Any, D: Any, M: Any, w1: float) -> None:
        present = [x for x in (K, D, M) if x is not None]
        self.sparse = any(sp.issparse(x) for x in present)
        self.n = int(present[0].shape[0])
        self.w1 = float(w1)
        if self.sparse:
            coos = [sp.coo_array(x) for x in (K, D, M) if x is not None]
            keys = [c.col.astype(np.int64) * self.n + c.row for c in coos]
            union = np.unique(np.concatenate(keys))
            self.indptr = np.searchsorted(union // self.n, np.arange(self.n + 1)).astype(np.int64)
            self.indices = union % self.n
            self.values = np.zeros((3, union.size))
            it = iter(zip(coos, keys, strict=True))
            for j, x in enumerate((K, D, M)):
                if x is not None:
                    c, key = next(it)
                    np.add.at(self.values[j], np.searchsorted(union, key), np.real(c.data))
        self._dense: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._csc: tuple[sp.csc_array, ...] | None = None
        if not self.sparse:
            z = np.zeros((self.n, self.n))
            self._dense = tuple(  # type: ignore[assignment]
                z if x is None else np.asarray(x, dtype=float) for x in (K, D, M)
            )

    @classmethod
    def from_csc(
        cls, indptr: np.ndarray, indices: np.ndarray, values: np.ndarray, w1: float
    ) -> Pencil:
        """From a CSC pattern and its values (rows ``K, D, M``) already summed by the caller.

        >>> KDM = np.array([[4.0], [0.0], [1.0]])  # K = 4, D = 0, M = 1 on one entry
        >>> p = Pencil.from_csc(np.array([0, 1]), np.array([0]), KDM, 1.0)
        >>> p.matrix(2).toarray()
        array([[0.+0.j]])
        """
        self = cls.__new__(cls)
        self.sparse, self.n, self.w1 = True, int(indptr.size - 1), float(w1)
        self.indptr = np.asarray(indptr, dtype=np.int64)
        self.indices = np.asarray(indices, dtype=np.int64)
        self.values = np.asarray(values, dtype=float)
        self._dense, self._csc = None, None
        return self

    def s(self, ns: np.ndarray) -> np.ndarray:
        """``s = i n w1`` per harmonic."""
        return 1j * self.w1 * np.asarray(ns, dtype=float)

    def dense(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(K_0, D_0, M_0)`` as dense arrays (made once; small systems only)."""
        if self._dense is None:
            K, D, M = (x.toarray() for x in self._matrices())
            self._dense = (K, D, M)
        assert self._dense is not None
        return self._dense

    def _matrices(self) -> tuple[sp.csc_array, ...]:
        if self._csc is None:
            shape = (self.n, self.n)
            self._csc = tuple(
                sp.csc_array((v, self.indices, self.indptr), shape) for v in self.values
            )
        return self._csc

    def matrix(self, n: int) -> Any:
        """``A0(n)``: sparse CSC (real for ``n = 0``) or a dense array."""
        s = complex(self.s(np.array([n]))[0])
        if self.sparse:
            k0, d0, m0 = self.values
            data = k0 + s * d0 + (s * s) * m0 if n else k0.copy()
            return sp.csc_array((data, self.indices.copy(), self.indptr.copy()), (self.n,) * 2)
        K, D, M = self.dense()
        return K + s * D + (s * s) * M if n else K.copy()

    def apply(self, X: np.ndarray, ns: np.ndarray) -> np.ndarray:
        """Rows ``A0(n_i) x_i`` for the rows ``x_i`` of ``X`` (by matrix products)."""
        s = self.s(ns)[:, None]
        if self.sparse:
            K, D, M = (
                sp.csc_array((v, self.indices, self.indptr), (self.n,) * 2) for v in self.values
            )
            KX, DX, MX = ((A @ X.T).T for A in (K, D, M))
        else:
            KX, DX, MX = (X @ A.T for A in self.dense())
        return KX + s * DX + (s * s) * MX
