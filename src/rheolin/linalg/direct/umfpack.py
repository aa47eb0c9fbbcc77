"""UMFPACK (SuiteSparse) through ``kvxopt`` as a :class:`~rheolin.linalg.direct.Analysis`:
one symbolic analysis (column ordering) per pattern, reused by every numeric factorization.

kvxopt's factor objects are opaque, so the memory of a factor is measured as the growth of
the resident memory during the first numeric factorization (an estimate; the next ones are
assumed alike)."""

from __future__ import annotations

import importlib
from typing import Any

import numpy as np

from ..errors import SingularBlockError

__all__ = ["UmfpackBackend"]


def _kvx() -> Any:
    """The kvxopt module (untyped: its stubs do not know NumPy arrays)."""
    return importlib.import_module("kvxopt")


def _umf() -> Any:
    return importlib.import_module("kvxopt.umfpack")


def _rss() -> int:
    try:
        with open("/proc/self/statm") as fh:
            import os

            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except OSError:  # pragma: no cover - not Linux
        return 0


class UmfpackFactor:
    """A numeric UMFPACK factor."""

    def __init__(self, owner: UmfpackBackend, A: Any, numeric: Any, nbytes: int) -> None:
        self._owner, self._A, self._F = owner, A, numeric
        self.nbytes = nbytes

    def solve(self, B: np.ndarray) -> np.ndarray:
        """``A^-1 B`` (``B``: ``n`` or ``n x k``)."""
        matrix, umfpack = _kvx().matrix, _umf()
        if self._F is None:
            raise RuntimeError("this UMFPACK factor was released")
        B = np.asarray(B)
        one = B.ndim == 1
        Bm = B.reshape(B.shape[0], -1)
        if self._owner.complex:
            X = matrix(np.asfortranarray(Bm, dtype=complex))
            umfpack.solve(self._A, self._F, X)
            out = np.array(X, dtype=complex)
        else:
            parts = []
            for part in (Bm.real, Bm.imag) if np.iscomplexobj(Bm) else (Bm,):
                X = matrix(np.asfortranarray(part, dtype=float))
                umfpack.solve(self._A, self._F, X)
                parts.append(np.array(X, dtype=float))
            out = parts[0] + 1j * parts[1] if len(parts) == 2 else parts[0]
        return out[:, 0] if one else out

    def release(self) -> None:
        """Drop the factor."""
        self._F = None


class UmfpackBackend:
    """UMFPACK on a fixed CSC pattern (see the module)."""

    name = "umfpack"
    releases_gil = True

    def __init__(
        self,
        indptr: np.ndarray,
        indices: np.ndarray,
        complex_values: bool,
        sample: np.ndarray | None = None,
    ) -> None:
        umfpack = _umf()
        self.n = int(indptr.size - 1)
        self.complex = complex_values
        self._I = np.asarray(indices, dtype=np.int64)
        self._J = np.repeat(np.arange(self.n, dtype=np.int64), np.diff(indptr))
        values = np.ones(indices.size) if sample is None else np.asarray(sample)
        self._symbolic = umfpack.symbolic(self._matrix(values))
        self.factor_bytes = int(indices.size * 40 * (20 if complex_values else 12))
        self._measured = False

    def _matrix(self, data: np.ndarray) -> Any:
        kvx = _kvx()
        matrix, spmatrix = kvx.matrix, kvx.spmatrix
        tc = "z" if self.complex else "d"
        values = matrix(np.asarray(data, dtype=complex if self.complex else float))
        return spmatrix(values, matrix(self._I), matrix(self._J), (self.n, self.n), tc)

    def factor(self, data: np.ndarray) -> UmfpackFactor:
        """Factorize the CSC values ``data`` with the shared symbolic analysis."""
        umfpack = _umf()
        A = self._matrix(data)
        before = _rss()
        try:
            F = umfpack.numeric(A, self._symbolic)
        except ArithmeticError as exc:
            raise SingularBlockError(-1, f"UMFPACK: {exc}") from None
        if not self._measured:
            self._measured = True
            grown = _rss() - before
            if grown > 0:
                self.factor_bytes = int(grown)
        return UmfpackFactor(self, A, F, self.factor_bytes)
