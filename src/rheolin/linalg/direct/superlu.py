"""SciPy's SuperLU as a :class:`~rheolin.linalg.direct.Analysis` (no reusable analysis: SciPy
orders every factorization anew; it holds the GIL)."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import SingularBlockError

__all__ = ["SuperLUBackend", "backward_error", "probe_vector", "splu_checked"]

#: Supernode settings: no relaxed supernodes (``relax=1``), panels of one column. SciPy's
#: defaults pad supernodes with explicit zeros, which on the banded chain of a finely meshed
#: shaft take several times the memory and time of the entries themselves.
COMPACT: dict[str, Any] = {"relax": 1, "panel_size": 1}
#: SuperLU options for structurally symmetric structural matrices. Threshold pivoting that
#: prefers the diagonal keeps the fill of the symmetric ordering; partial pivoting (SuperLU's
#: default) multiplied the fill by 80 on indefinite mid-range harmonics of a chain.
SPLU_OPTIONS: dict[str, Any] = {
    "permc_spec": "MMD_AT_PLUS_A",
    "diag_pivot_thresh": 0.1,
    "options": {"SymmetricMode": True},
    **COMPACT,
}
#: A pivot below this times the largest is round-off: the matrix is singular.
PIVOT_RTOL = 1e3 * np.finfo(float).eps
#: A diagonal-preferring factor whose probe solve has a larger backward error than this
#: (:func:`backward_error`) has grown its pivots: partial pivoting instead.
PROBE_BACKWARD = 1e-11


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


def backward_error(A: Any, x: np.ndarray, b: np.ndarray) -> float:
    """Normwise backward error ``||b - A x|| / (||A|| ||x|| + ||b||)`` in the infinity norm:
    the smallest relative change of ``A`` and ``b`` that makes ``x`` exact. Unlike the
    relative residual ``||b - A x|| / ||b||`` it does not grow with the stiffness scale.

    Two masses on springs of 1 and 2 N/m to ground, tied by a stiff 1e13 N/m spring:

    >>> A = sp.csc_array(np.array([[1e13 + 1, -1e13], [-1e13, 1e13 + 2]]))
    >>> b = np.array([0.0, 1.0]); x = np.linalg.solve(A.toarray(), b)
    >>> relative = np.abs(b - A @ x).max() / np.abs(b).max()
    >>> bool(relative > 1e-6), bool(backward_error(A, x, b) < 1e-15)
    (True, True)
    """
    r = float(np.max(np.abs(b - A @ x), initial=0.0))
    norm_a = float(np.max(np.asarray(abs(A).sum(axis=1)), initial=0.0))
    scale = norm_a * float(np.max(np.abs(x), initial=0.0)) + float(np.max(np.abs(b), initial=0.0))
    return r / scale if scale > 0 else r


def splu_checked(A: Any, n: int = -1) -> Any:
    """Sparse LU with diagonal-preferring pivoting, checked by the backward error of a probe
    solve (:func:`backward_error`, the measure of pivot growth); partial pivoting when that
    is above :data:`PROBE_BACKWARD`. Raises :class:`SingularBlockError`.

    A real matrix is singular when a pivot is below :data:`PIVOT_RTOL` times the largest. A
    complex one (a harmonic ``n != 0``) when the probe's amplification, a lower estimate of
    its condition number, exceeds ``1 / PIVOT_RTOL`` (SciPy keeps a copy of ``L`` and ``U``
    on a factor once they are read, which would double the memory each of the many held
    complex factors takes). The amplification is that of the symmetrically scaled matrix
    ``S^-1 A S^-1``, ``S = diag(sqrt|A_ii|)``: ``||S^-1 A S^-1||_F ||S x|| / ||b||`` with
    ``A x = S b``. An undamped resonance makes it grow without bound in any scaling, where the
    unscaled one also grows with the units and the mesh (translations against rotations of
    short beam elements): a shaft meshed to 50,000 DOF has an unscaled amplification of
    1.6e13 at every harmonic, and 1.6e9 scaled.

    >>> K = sp.csc_array(np.array([[1e8, 0, 0], [0, 2.0, -1.0], [0, -1.0, 2.0]]))
    >>> M = sp.identity(3, format="csc")
    >>> lu = splu_checked(sp.csc_array(K - 1.0 * M + 1e-3j * M), n=1)  # off resonance
    >>> try:
    ...     splu_checked(sp.csc_array(K - 3.0 * M + 0j * M), n=1)  # at the mode of 3 rad^2/s^2
    ... except SingularBlockError as exc:
    ...     print("singular at harmonic", exc.n)
    singular at harmonic 1
    """
    b = probe_vector(A.shape[0])
    real = not np.iscomplexobj(A)
    scale = None if real else _jacobi_scale(A)
    lu = None
    for options in (SPLU_OPTIONS, {"permc_spec": "MMD_AT_PLUS_A", **COMPACT}):
        try:
            lu = spla.splu(A, **options)
        except RuntimeError as exc:
            raise SingularBlockError(n, str(exc)) from None
        if real:
            diag = np.abs(lu.U.diagonal())
            if diag.size and diag.min() <= PIVOT_RTOL * diag.max():
                raise SingularBlockError(n, "pivot below round-off")
        if scale is None:
            x = lu.solve(b.astype(A.dtype))
        else:
            d, norm_s = scale
            both = lu.solve(np.column_stack([b, d * b]).astype(A.dtype))
            x = both[:, 0]
            gain = float(norm_s * np.linalg.norm(d * both[:, 1]) / np.linalg.norm(b))
            if not gain * PIVOT_RTOL < 1.0:
                raise SingularBlockError(n, f"condition number above {gain:.2g}")
        if backward_error(A, x, b) <= PROBE_BACKWARD:
            return lu
    return lu


def _jacobi_scale(A: Any) -> tuple[np.ndarray, float]:
    """``s = sqrt|A_ii|`` (1 where the diagonal is zero) and ``||S^-1 A S^-1||_F``."""
    A = sp.csc_array(A)
    d = np.sqrt(np.abs(A.diagonal()))
    d[~(d > 0)] = 1.0
    cols = np.repeat(np.arange(A.shape[1]), np.diff(A.indptr))
    scaled = A.data / (d[A.indices] * d[cols])
    return d, float(np.linalg.norm(scaled))


class SuperLUFactor:
    """A SuperLU factor; a real factor solves complex right-hand sides part by part."""

    def __init__(self, lu: Any, complex_values: bool) -> None:
        self._lu, self._complex = lu, complex_values
        item = 16 if complex_values else 8
        # lu.nnz: the entries SuperLU stores (reading lu.L or lu.U would keep copies of them)
        self.nbytes = int(lu.nnz * (item + 4) + 16 * lu.shape[0])

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
