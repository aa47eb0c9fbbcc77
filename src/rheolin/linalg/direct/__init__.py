"""Sparse direct factorizations of one matrix pattern, by interchangeable backends.

``analyze(backend, indptr, indices, complex_values)`` returns an :class:`Analysis` of the CSC
pattern (the symbolic part, reused by every matrix with that pattern: every harmonic of every
speed); ``analysis.factor(data)`` factorizes the values ``data`` on it and returns a
:class:`Factor` with ``solve(B)``, ``nbytes`` and ``release()``.

Backends (``SPARSE_BACKENDS``), fastest first as measured (``bench/backends.py``):

* ``pardiso``: MKL PARDISO (``pip install mkl``), METIS ordering, multithreaded, releases the
  GIL, reports its factor size before factorizing.
* ``umfpack``: UMFPACK from SuiteSparse through ``kvxopt`` (a wheel that bundles it).
* ``superlu``: SciPy's SuperLU (always there; holds the GIL; slow on 3-D meshes).

``"auto"`` takes the first installed one.
"""

from __future__ import annotations

import functools
import logging
from typing import Protocol

import numpy as np

__all__ = [
    "SPARSE_BACKENDS",
    "Analysis",
    "Factor",
    "analyze",
    "available_backends",
    "resolve_backend",
]

log = logging.getLogger(__name__)

#: Sparse direct backends, in the order ``"auto"`` tries them.
SPARSE_BACKENDS = ("pardiso", "umfpack", "superlu")


class Factor(Protocol):
    """A numeric factorization: ``solve`` for one or many right-hand sides."""

    nbytes: int

    def solve(self, B: np.ndarray) -> np.ndarray: ...

    def release(self) -> None: ...


class Analysis(Protocol):
    """The symbolic analysis of one pattern; ``factor`` makes numeric factors on it."""

    name: str
    #: Bytes one numeric factor takes (an estimate before the first factorization).
    factor_bytes: int
    #: True when the factorization runs without the GIL (threads can overlap).
    releases_gil: bool

    def factor(self, data: np.ndarray) -> Factor: ...


@functools.cache
def available_backends() -> tuple[str, ...]:
    """The sparse backends installed here, fastest first.

    >>> "superlu" in available_backends()
    True
    """
    out = []
    for name in SPARSE_BACKENDS:
        try:
            if name == "pardiso":
                from .pardiso import load_mkl

                if load_mkl() is None:
                    continue
            elif name == "umfpack":
                import kvxopt.umfpack  # noqa: F401
        except ImportError:
            continue
        out.append(name)
    return tuple(out)


def resolve_backend(name: str) -> str:
    """The backend to use for ``name`` (``"auto"``: the fastest installed); a clear error
    when a named one is missing."""
    if name == "auto":
        return available_backends()[0]
    if name not in SPARSE_BACKENDS:
        allowed = ["auto", *SPARSE_BACKENDS]
        raise ValueError(f"`sparse_backend` must be one of {allowed}, got {name!r}")
    if name not in available_backends():
        hint = {"pardiso": "pip install mkl", "umfpack": "pip install kvxopt"}[name]
        raise ValueError(f"sparse backend {name!r} is not installed ({hint})")
    return name


def analyze(
    backend: str,
    indptr: np.ndarray,
    indices: np.ndarray,
    complex_values: bool,
    *,
    slots: int = 1,
    sample: np.ndarray | None = None,
) -> Analysis:
    """Symbolic analysis of the ``n x n`` CSC pattern ``indptr, indices`` by ``backend``.

    ``slots`` is how many numeric factors may be alive at once (PARDISO keeps them in one
    handle); ``sample`` a representative set of values (UMFPACK's analysis looks at them).

    >>> import scipy.sparse as sp
    >>> A = sp.csc_array(np.array([[4.0, 1.0], [1.0, 3.0]]))
    >>> f = analyze("superlu", A.indptr, A.indices, False).factor(A.data)
    >>> f.solve(np.array([1.0, 2.0])).round(6).tolist()
    [0.090909, 0.636364]
    """
    name = resolve_backend(backend)
    indptr = np.asarray(indptr, dtype=np.int64)
    indices = np.asarray(indices, dtype=np.int64)
    if name == "pardiso":
        from .pardiso import PardisoBackend

        return PardisoBackend(indptr, indices, complex_values, slots)
    if name == "umfpack":
        from .umfpack import UmfpackBackend

        return UmfpackBackend(indptr, indices, complex_values, sample)
    from .superlu import SuperLUBackend

    return SuperLUBackend(indptr, indices, complex_values)


def csc_pattern_key(indptr: np.ndarray, indices: np.ndarray) -> tuple[int, int, int]:
    """A cheap key of a pattern (size, nnz, hash) for caching analyses."""
    return (int(indptr.size), int(indices.size), hash(indices.tobytes()) ^ hash(indptr.tobytes()))
