"""MKL PARDISO through ``ctypes`` (the ``mkl`` wheel ships ``libmkl_rt``).

pypardiso, the maintained binding, handles real matrices only (``mtype = 11``); the blocks
``A0(n) = K + i n w1 D - (n w1)^2 M`` are complex, so this module calls ``pardiso`` itself:
``mtype = 13`` (complex, unsymmetric: gyroscopic and circulatory terms make ``A0(n)``
unsymmetric) or ``11`` for the real block ``n = 0``. One handle per pattern holds the
symbolic analysis (METIS nested dissection, phase 11) and up to ``slots`` numeric factors
(``maxfct``), so every harmonic of every speed reuses one analysis. ``ctypes`` releases the
GIL during the call and PARDISO itself is multithreaded (OpenMP, ``MKL_NUM_THREADS``).
Phase 11 also reports the factor size and the peak memory, which the memory estimate uses.
"""

from __future__ import annotations

import ctypes
import glob
import os
import site
import sys
import threading
from collections.abc import Iterator
from ctypes.util import find_library
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import SingularBlockError

__all__ = ["PardisoAnalysis", "load_mkl"]

_LIB: Any = None
_LOCK = threading.Lock()


def load_mkl() -> Any:
    """The ``pardiso`` entry point of ``libmkl_rt``, or None when MKL is not installed."""
    global _LIB
    with _LOCK:
        if _LIB is not None:
            return _LIB or None
        for path in _mkl_candidates():
            if not path:
                continue
            try:
                lib = ctypes.CDLL(path)
                fn = lib.pardiso
            except (OSError, AttributeError):
                continue
            fn.restype = None
            _LIB = lib
            return lib
        _LIB = False
        return None


def _mkl_candidates() -> Iterator[str | None]:
    """Where ``libmkl_rt`` may be, cheapest first: the environment, the loader's path, the
    ``lib`` directories the ``mkl`` wheel installs into, and only then a recursive search of
    the environment (it reads every directory of site-packages: about a second)."""
    yield os.environ.get("RHEOLIN_MKL_RT")
    yield find_library("mkl_rt")
    roots = (sys.prefix, site.getuserbase())
    for root in roots:
        yield from sorted(glob.glob(f"{root}/[Ll]ib*/libmkl_rt.so*"))
    for root in roots:
        yield from sorted(glob.glob(f"{root}/[Ll]ib*/**/libmkl_rt.so*", recursive=True))


_INT = ctypes.POINTER(ctypes.c_int32)
_PTR = ctypes.c_void_p

#: PARDISO error codes (``error`` argument).
_ERRORS = {
    -1: "input inconsistent",
    -2: "not enough memory",
    -3: "reordering problem",
    -4: "zero pivot, numerical factorization or iterative refinement problem",
    -5: "unclassified (internal) error",
    -6: "reordering failed",
    -7: "diagonal matrix is singular",
    -8: "32-bit integer overflow problem",
    -9: "not enough memory for OOC",
    -10: "error opening OOC files",
    -11: "read/write error with OOC files",
}


class PardisoAnalysis:
    """Symbolic analysis of one CSC pattern; numeric factors in ``slots`` slots.

    Parameters
    ----------
    indptr, indices
        CSC pattern of the ``n x n`` matrix (rows sorted within columns).
    complex_values
        True for ``mtype = 13``, False for real unsymmetric (``11``).
    slots
        Numeric factors held at once (PARDISO's ``maxfct``).
    """

    def __init__(
        self,
        indptr: np.ndarray,
        indices: np.ndarray,
        complex_values: bool,
        slots: int = 1,
        matching: bool = False,
        refinement: int = 2,
    ) -> None:
        lib = load_mkl()
        if lib is None:
            raise ImportError("MKL (libmkl_rt) not found: pip install mkl")
        self._fn = lib.pardiso
        n = int(indptr.size - 1)
        self.n, self.slots = n, max(1, int(slots))
        self.dtype = np.complex128 if complex_values else np.float64
        self.mtype = 13 if complex_values else 11
        # CSR of the same matrix, with the diagonal present (PARDISO's preference)
        csc = sp.csc_array(
            (np.arange(1, indices.size + 1, dtype=np.float64), indices, indptr), shape=(n, n)
        )
        csr = sp.csr_array(csc + sp.eye_array(n, format="csr") * 0.5)  # marks the diagonal
        csr.sort_indices()
        marks = csr.data
        self._take = np.where(marks >= 1.0, np.floor(marks).astype(np.int64) - 1, -1)
        self.ia = (csr.indptr + 1).astype(np.int32)
        self.ja = (csr.indices + 1).astype(np.int32)
        self.nnz = int(self.ja.size)
        self.pt = np.zeros(64, dtype=np.int64)
        self.iparm = np.zeros(64, dtype=np.int32)
        self.iparm[0] = 1  # user-supplied parameters
        self.iparm[1] = 2  # METIS nested dissection
        # iterative refinement: at most this many steps on every solve; 0: two steps only
        # after perturbed pivots (each step is a product and a solve: 3x the plain solve)
        self.iparm[7] = refinement
        self.iparm[9] = 13  # pivot perturbation 1e-13
        # scaling and weighted matching are computed from the values in the analysis, which
        # serves every harmonic: off by default (pivot perturbation + refinement instead)
        self.iparm[10] = int(matching)
        self.iparm[12] = int(matching)
        self.iparm[17] = -1  # report nnz of the factors
        self.iparm[26] = 0
        self._lock = threading.Lock()
        self._alive = True
        dummy = np.zeros(1, dtype=self.dtype)
        probe = np.ones(self.nnz, dtype=self.dtype)
        self._call(11, 1, probe, dummy, dummy, 1)
        #: Factor entries and memory per numeric factor (from the analysis) [bytes].
        self.factor_nnz = int(self.iparm[17])
        self.factor_bytes = 1024 * int(self.iparm[16])
        self.analysis_bytes = 1024 * int(max(self.iparm[14], self.iparm[15]))

    def _call(
        self, phase: int, mnum: int, a: np.ndarray, b: np.ndarray, x: np.ndarray, nrhs: int
    ) -> None:
        error = ctypes.c_int32(0)
        i32 = ctypes.c_int32
        self._fn(
            self.pt.ctypes.data_as(_PTR),
            ctypes.byref(i32(self.slots)),
            ctypes.byref(i32(mnum)),
            ctypes.byref(i32(self.mtype)),
            ctypes.byref(i32(phase)),
            ctypes.byref(i32(self.n)),
            a.ctypes.data_as(_PTR),
            self.ia.ctypes.data_as(_INT),
            self.ja.ctypes.data_as(_INT),
            ctypes.POINTER(ctypes.c_int32)(),
            ctypes.byref(i32(nrhs)),
            self.iparm.ctypes.data_as(_INT),
            ctypes.byref(i32(0)),
            b.ctypes.data_as(_PTR),
            x.ctypes.data_as(_PTR),
            ctypes.byref(error),
        )
        if error.value:
            msg = _ERRORS.get(error.value, f"error {error.value}")
            if error.value in (-4, -7):
                raise SingularBlockError(-1, f"PARDISO: {msg}")
            if error.value in (-2, -9):
                raise MemoryError(f"PARDISO phase {phase}: {msg}")
            raise RuntimeError(f"PARDISO phase {phase}: {msg}")

    def values(self, csc_data: np.ndarray) -> np.ndarray:
        """CSR values (with explicit zero diagonal where absent) from CSC ``data``."""
        out = np.zeros(self.nnz, dtype=self.dtype)
        have = self._take >= 0
        out[have] = csc_data[self._take[have]]
        return out

    def factor(self, slot: int, a: np.ndarray) -> int:
        """Numeric factorization of the CSR values ``a`` into ``slot`` (0-based); returns the
        number of perturbed pivots."""
        dummy = np.zeros(1, dtype=self.dtype)
        with self._lock:
            self._call(22, slot + 1, a, dummy, dummy, 1)
            return int(self.iparm[13])

    def solve(self, slot: int, a: np.ndarray, B: np.ndarray, trans: str = "N") -> np.ndarray:
        """Solve with the factor in ``slot`` for the columns of ``B`` (``n`` or ``n x k``);
        ``trans``: ``"N"`` (``A X = B``), ``"T"`` (``A^T X = B``) or ``"H"`` (``A^H X = B``)."""
        one = B.ndim == 1
        Bf = np.asfortranarray(B.reshape(self.n, -1), dtype=self.dtype)
        X = np.zeros_like(Bf)
        if Bf.shape[1] == 0:
            return X
        # iparm(12): 0 plain, 1 conjugate transposed, 2 transposed (CSR rows are our columns)
        mode = {"N": 0, "H": 1, "T": 2}[trans]
        if self.dtype == np.float64 and mode == 1:
            mode = 2
        with self._lock:
            self.iparm[11] = mode
            try:
                self._call(33, slot + 1, a, Bf, X, Bf.shape[1])
            finally:
                self.iparm[11] = 0
        return X[:, 0] if one else X

    def release(self, slot: int | None = None) -> None:
        """Free one slot's factor (``None``: everything, the analysis too)."""
        if not self._alive:
            return
        dummy = np.zeros(1, dtype=self.dtype)
        with self._lock:
            if slot is None:
                self._call(-1, 1, dummy, dummy, dummy, 1)
                self._alive = False
            else:
                self._call(0, slot + 1, dummy, dummy, dummy, 1)

    def __del__(self) -> None:
        try:
            self.release()
        except Exception:  # pragma: no cover - interpreter shutdown
            pass


class PardisoFactor:
    """One numeric factor in a slot of a :class:`PardisoBackend`."""

    def __init__(self, owner: PardisoBackend, slot: int, a: np.ndarray) -> None:
        self._owner, self._slot, self._a = owner, slot, a
        self.nbytes = owner.factor_bytes + a.nbytes

    def solve(self, B: np.ndarray, trans: str = "N") -> np.ndarray:
        """``A^-1 B`` (``B``: ``n`` or ``n x k``); ``trans="T"``/``"H"`` solves with the
        transpose / conjugate transpose."""
        if self._slot < 0:
            raise RuntimeError("this PARDISO factor was released")
        B = np.asarray(B)
        if not np.iscomplexobj(self._a) and np.iscomplexobj(B):
            both = self._owner.analysis.solve(
                self._slot,
                self._a,
                np.column_stack([B.real, B.imag]).reshape(B.shape[0], -1),
                trans,
            )
            k = both.shape[1] // 2
            X = both[:, :k] + 1j * both[:, k:]
            return X[:, 0] if B.ndim == 1 else X
        return self._owner.analysis.solve(self._slot, self._a, B, trans)

    def release(self) -> None:
        """Free the factor's slot."""
        if self._slot >= 0:
            self._owner.free(self._slot)
            self._slot = -1

    def __del__(self) -> None:
        try:
            self.release()
        except Exception:  # pragma: no cover - interpreter shutdown
            pass


class PardisoBackend:
    """:class:`~rheolin.linalg.direct.Analysis` by MKL PARDISO (see the module)."""

    name = "pardiso"
    releases_gil = True

    def __init__(
        self,
        indptr: np.ndarray,
        indices: np.ndarray,
        complex_values: bool,
        slots: int = 1,
        refinement: int = 2,
    ) -> None:
        self.analysis = PardisoAnalysis(
            indptr, indices, complex_values, slots, refinement=refinement
        )
        self.factor_bytes = self.analysis.factor_bytes
        self._free = list(range(self.analysis.slots))[::-1]
        self._lock = threading.Lock()

    def factor(self, data: np.ndarray) -> PardisoFactor:
        """Factorize CSC values ``data`` into a free slot."""
        with self._lock:
            if not self._free:
                raise RuntimeError(f"all {self.analysis.slots} PARDISO slots are in use")
            slot = self._free.pop()
        a = self.analysis.values(np.asarray(data, dtype=self.analysis.dtype))
        try:
            self.analysis.factor(slot, a)
        except Exception:
            self.free(slot)
            raise
        return PardisoFactor(self, slot, a)

    def free(self, slot: int) -> None:
        """Return a slot (its factor's memory) to the pool."""
        try:
            self.analysis.release(slot)
        finally:
            with self._lock:
                self._free.append(slot)
