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

``"auto"`` chooses by the pattern (:func:`auto_backend`): PARDISO where factorizing is costly
(2-D and 3-D meshes); SuperLU on banded patterns (shaft chains, beam-like models), where the
cost of each solve, which an iterative method pays per harmonic and iteration, dominates.
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
    "auto_backend",
    "available_backends",
    "envelope_work",
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


#: Envelope work (flops of a banded LU after reverse Cuthill-McKee) above which the
#: factorization is costly enough for PARDISO's per-call overhead not to matter (between the
#: chains and the meshes whose envelope work bench/backends.py prints).
CHEAP_WORK = 1e8


def envelope_work(indptr: np.ndarray, indices: np.ndarray, n: int) -> float:
    """``sum_i b_i^2`` over the rows of the symmetrized pattern after reverse Cuthill-McKee
    (``b_i``: the row's distance to its first entry): the work of a banded LU, a cheap
    (``O(nnz)``) measure of how costly factorizing the pattern is.

    >>> import scipy.sparse as sp
    >>> A = sp.csc_array(sp.diags_array([1.0, 2.0, 1.0], offsets=[-1, 0, 1], shape=(100, 100)))
    >>> envelope_work(A.indptr, A.indices, 100)  # tridiagonal: b_i = 1 except the first row
    99.0
    """
    import scipy.sparse as sp
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    P = sp.csr_array((np.ones(indices.size), indices, indptr), shape=(n, n))
    S = sp.csr_array(P + P.T)
    perm = reverse_cuthill_mckee(S, symmetric_mode=True)
    Q = sp.coo_array(S[perm][:, perm])
    first = np.full(n, n, dtype=np.int64)
    np.minimum.at(first, Q.row, Q.col)
    b = np.maximum(np.arange(n) - np.minimum(first, np.arange(n)), 0).astype(float)
    return float(np.sum(b * b))


@functools.lru_cache(maxsize=16)
def _auto_for(n: int, digest: int, size: int, work: float) -> str:
    if work > CHEAP_WORK:
        return available_backends()[0]  # PARDISO, else UMFPACK, else SuperLU
    return "superlu"  # cheap factors: SuperLU's solves cost least per call


def auto_backend(indptr: np.ndarray, indices: np.ndarray, n: int) -> str:
    """The backend ``"auto"`` takes for this pattern: when its envelope work exceeds
    :data:`CHEAP_WORK` the fastest factorization installed (PARDISO, UMFPACK, SuperLU, in
    that order); below, SuperLU, whose factorizations are as fast there and whose solves cost
    less per call than UMFPACK's and PARDISO's (``bench/backends.py``): an iterative method
    pays a solve per harmonic at every iteration."""
    digest = hash((np.asarray(indptr).tobytes(), np.asarray(indices).tobytes()))
    return _auto_for(n, digest, indices.size, envelope_work(indptr, indices, n))


def resolve_backend(name: str, pattern: tuple[np.ndarray, np.ndarray, int] | None = None) -> str:
    """The backend to use for ``name`` (``"auto"``: by ``pattern`` ``(indptr, indices, n)``,
    :func:`auto_backend`, else the first installed); a clear error when a named one is
    missing."""
    if name == "auto":
        return auto_backend(*pattern) if pattern is not None else available_backends()[0]
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
