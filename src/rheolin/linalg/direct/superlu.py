"""SciPy's SuperLU as a :class:`~rheolin.linalg.direct.Analysis` (no reusable analysis: SciPy
orders every factorization anew; it holds the GIL)."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import SingularBlockError

__all__ = ["SuperLUBackend", "probe_vector", "splu_checked"]

#: SuperLU options for structurally symmetric structural matrices. Threshold pivoting that
#: prefers the diagonal keeps the fill of the symmetric ordering; partial pivoting (SuperLU's
#: default) multiplied the fill by 80 on indefinite mid-range harmonics of a chain.
SPLU_OPTIONS: dict[str, Any] = {
    "permc_spec": "MMD_AT_PLUS_A",
    "diag_pivot_thresh": 0.1,
    "options": {"SymmetricMode": True},
}
#: A pivot below this times the largest is round-off: the matrix is singular.
PIVOT_RTOL = 1e3 * np.finfo(float).eps


@functools.lru_cache(maxsize=8)
def probe_vector(n: int) -> np.ndarray:
    """The fixed right-hand side (read-only) on which factors of size ``n`` are checked.

    >>> v = probe_vector(3)
    >>> v.shape, bool(np.array_equal(v, probe_vector(3))), v.flags.writeable
    ((3,), True, False)
    """
    b = np.random.default_rng(n).standard_normal(n)
    b.setflags(write=False)
    return b


def splu_checked(A: Any, n: int = -1) -> Any:
    """Sparse LU with diagonal-preferring pivoting, checked on a probe right-hand side;
    partial pivoting when that was inaccurate. Raises :class:`SingularBlockError`."""
    b = probe_vector(A.shape[0])
    lu = None
    for options in (SPLU_OPTIONS, {"permc_spec": "MMD_AT_PLUS_A"}):
        try:
            lu = spla.splu(A, **options)
        except RuntimeError as exc:
            raise SingularBlockError(n, str(exc)) from None
        diag = np.abs(lu.U.diagonal())
        if diag.size and diag.min() <= PIVOT_RTOL * diag.max():
            raise SingularBlockError(n, "pivot below round-off")
        x = lu.solve(b.astype(A.dtype))
        if np.linalg.norm(A @ x - b) <= 1e-11 * np.linalg.norm(b):
            return lu
    return lu


class SuperLUFactor:
    """A SuperLU factor; a real factor solves complex right-hand sides part by part."""

    def __init__(self, lu: Any, complex_values: bool) -> None:
        self._lu, self._complex = lu, complex_values
        item = 16 if complex_values else 8
        self.nbytes = int((lu.L.nnz + lu.U.nnz) * (item + 4) + 16 * lu.shape[0])

    def solve(self, B: np.ndarray) -> np.ndarray:
        """``A^-1 B`` (``B``: ``n`` or ``n x k``)."""
        if self._lu is None:
            raise RuntimeError("this SuperLU factor was released")
        B = np.asarray(B)
        if self._complex:
            return np.asarray(self._lu.solve(B.astype(complex)))
        if not np.iscomplexobj(B):
            return np.asarray(self._lu.solve(np.ascontiguousarray(B, dtype=float)))
        if B.ndim == 1:
            both = self._lu.solve(np.column_stack([B.real, B.imag]))
            return np.asarray(both[:, 0] + 1j * both[:, 1])
        re = self._lu.solve(np.ascontiguousarray(B.real))
        return np.asarray(re + 1j * self._lu.solve(np.ascontiguousarray(B.imag)))

    def release(self) -> None:
        """Drop the factor."""
        self._lu = None


class SuperLUBackend:
    """SuperLU on a fixed CSC pattern."""

    name = "superlu"
    releases_gil = False

    def __init__(self, indptr: np.ndarray, indices: np.ndarray, complex_values: bool) -> None:
        self.indptr = np.asarray(indptr, dtype=np.int32)
        self.indices = np.asarray(indices, dtype=np.int32)
        self.n = int(indptr.size - 1)
        self.complex = complex_values
        # no symbolic estimate from SciPy: 40 entries per nonzero until the first factor says
        self.factor_bytes = int(indices.size * 40 * (20 if complex_values else 12))

    def factor(self, data: np.ndarray) -> SuperLUFactor:
        """Factorize the CSC values ``data``."""
        dtype = complex if self.complex else float
        values = np.ascontiguousarray(data, dtype=dtype)
        A = sp.csc_array((values, self.indices, self.indptr), (self.n,) * 2)
        f = SuperLUFactor(splu_checked(A), self.complex)
        self.factor_bytes = f.nbytes
        return f
