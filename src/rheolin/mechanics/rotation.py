"""Exact Fourier coefficients of uniformly rotating body-frame quantities (docs/rotating-bodies.md).

A body spinning at ``W = s * w1`` about the unit axis ``e`` has the rotation

    R(t) = exp(W t [e]x) = P0 + Pp exp(i W t) + Pm exp(-i W t),
    P0 = e e^T,  Pp, Pm = (I - e e^T -+ i [e]x) / 2,

so every product of a constant body-frame matrix with ``R`` and ``R^T`` is a *finite* Fourier
series with harmonics ``0, +-s, +-2s`` (in units of ``w1``). Nothing here samples in time.

A Fourier series is a ``dict[int, ndarray]`` from the harmonic index ``k`` (units of ``w1``) to
its coefficient; both signs are present and ``X_{-k} = conj(X_k)``. Harmonic 0 is returned real.
"""

from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction

import numpy as np

from ..errors import ModelError

__all__ = [
    "add_series",
    "circulatory_matrix",
    "clean_series",
    "derivative",
    "rotate_body_matrix",
    "rotate_body_vector",
    "rotation_series",
    "series_product",
    "skew",
    "unit_axis",
]

Series = dict[int, np.ndarray]


def unit_axis(axis: object, name: str = "axis") -> np.ndarray:
    """Return ``axis`` as a unit 3-vector; raise :class:`ModelError` if it is not one.

    >>> unit_axis([0, 0, 2.0])
    array([0., 0., 1.])
    """
    a = np.asarray(axis, dtype=float).reshape(-1)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ModelError(f"`{name}` must be a finite 3-vector, got {axis!r}")
    n = float(np.linalg.norm(a))
    if n == 0.0:
        raise ModelError(f"`{name}` must be nonzero")
    return a / n


def transverse_basis(axis: object) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors ``(a, b)`` spanning the plane normal to ``axis``, right-handed about it
    (``b = e x a``): ``a = e x x`` normalized (``e x y`` for an axis near x). A motion
    ``a + i b`` whirls forward about the axis.

    >>> a, b = transverse_basis([0, 0, 1.0])
    >>> a.tolist(), b.tolist()
    ([0.0, 1.0, 0.0], [-1.0, 0.0, 0.0])
    """
    e = unit_axis(axis)
    a = np.cross(e, [1.0, 0.0, 0.0] if abs(e[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    return a, np.cross(e, a)


def skew(a: np.ndarray) -> np.ndarray:
    """Cross-product matrix ``[a]x`` (``skew(a) @ b == cross(a, b)``); ``a`` may be complex.

    >>> skew(np.array([0.0, 0.0, 1.0])) @ np.array([1.0, 0.0, 0.0])
    array([0., 1., 0.])
    """
    a = np.asarray(a)
    z = np.zeros((), dtype=a.dtype)
    return np.array([[z, -a[2], a[1]], [a[2], z, -a[0]], [-a[1], a[0], z]])


def _spin(s: object) -> int:
    """Accept ints, NumPy integers and whole :class:`fractions.Fraction` values."""
    if isinstance(s, Fraction) and s.denominator == 1:
        return int(s)
    if isinstance(s, bool) or not isinstance(s, (int, np.integer)):
        raise ModelError(f"spin harmonic `s` must be an integer, got {s!r}")
    return int(s)


def rotation_series(axis: object, s: int) -> Series:
    """Fourier coefficients of ``R(t) = exp(s w1 t [e]x)``: keys ``0, s, -s``.

    Parameters
    ----------
    axis
        Spin axis ``e`` (normalized here).
    s
        Spin harmonic: the body speed is ``W = s * w1``. ``s = 0`` gives ``{0: I}``.

    Examples
    --------
    >>> R = rotation_series([0, 0, 1], 1)
    >>> sorted(R), R[1][:2, :2]
    ([-1, 0, 1], array([[0.5+0.j , 0. +0.5j],
           [0. -0.5j, 0.5+0.j ]]))
    """
    e = unit_axis(axis)
    s = _spin(s)
    if s == 0:
        return {0: np.eye(3)}
    P0 = np.outer(e, e)
    Pp = 0.5 * (np.eye(3) - P0 - 1j * skew(e))
    return {0: P0, s: Pp, -s: Pp.conj()}


def derivative(series: Series, w1: float, order: int = 1) -> Series:
    """Time derivative of a Fourier series: coefficient ``k`` times ``(i k w1)^order``.

    >>> derivative({1: np.array([1.0 + 0j]), -1: np.array([1.0 + 0j])}, 2.0)
    {1: array([0.+2.j]), -1: array([0.-2.j])}
    """
    out: Series = {}
    for k, v in series.items():
        if k != 0:
            out[k] = (1j * k * w1) ** order * np.asarray(v)
    return out


def series_product(
    a: Series, b: Series, op: Callable[[np.ndarray, np.ndarray], np.ndarray] = np.matmul
) -> Series:
    """Fourier coefficients of ``op(a(t), b(t))`` for a bilinear ``op`` (exact convolution).

    >>> c = series_product({1: np.eye(2), -1: np.eye(2)}, {1: np.eye(2), -1: np.eye(2)})
    >>> sorted(c), float(c[0][0, 0])
    ([-2, 0, 2], 2.0)
    """
    out: Series = {}
    for ka, va in a.items():
        for kb, vb in b.items():
            v = op(va, vb)
            k = ka + kb
            out[k] = out[k] + v if k in out else v
    return out


def add_series(*series: Series) -> Series:
    """Sum of Fourier series (union of harmonics).

    >>> add_series({0: np.ones(1)}, {0: np.ones(1), 2: 1j * np.ones(1)})
    {0: array([2.]), 2: array([0.+1.j])}
    """
    out: Series = {}
    for ser in series:
        for k, v in ser.items():
            out[k] = out[k] + v if k in out else np.array(v)
    return {k: out[k] for k in sorted(out)}


def clean_series(series: Series, rtol: float = 1e-13) -> Series:
    """Drop coefficients below ``rtol`` times the largest; make harmonic 0 real.

    >>> clean_series({0: np.array([1.0 + 1e-20j]), 2: np.array([1e-18 + 0j])})
    {0: array([1.])}
    """
    scale = max((float(np.max(np.abs(v))) for v in series.values() if np.size(v)), default=0.0)
    out: Series = {}
    for k in sorted(series):
        v = np.asarray(series[k])
        if k == 0:
            out[0] = np.real(v).astype(float)
        elif scale > 0.0 and np.max(np.abs(v)) > rtol * scale:
            out[k] = v.astype(complex)
    if 0 not in out:
        shape = next(iter(series.values())).shape if series else ()
        out[0] = np.zeros(shape)
    return {k: out[k] for k in sorted(out)}


def _blocks(x: np.ndarray, name: str) -> int:
    if x.ndim != 2 or x.shape[0] != x.shape[1] or x.shape[0] % 3:
        raise ModelError(
            f"`{name}` must be a square matrix whose size is a multiple of 3, got shape {x.shape}"
        )
    return x.shape[0] // 3


def _sandwich(A: Series, X: np.ndarray, B: Series) -> Series:
    """Coefficients of ``At X Bt^T`` with ``At, Bt`` block-diagonal repeats of 3x3 series."""
    n = X.shape[0] // 3
    X4 = X.reshape(n, 3, n, 3)
    out: Series = {}
    for ka, Pa in A.items():
        left = np.einsum("ac,icjd->iajd", Pa, X4)
        for kb, Pb in B.items():
            v = np.einsum("iajd,bd->iajb", left, Pb).reshape(3 * n, 3 * n)
            k = ka + kb
            out[k] = out[k] + v if k in out else v
    return out


def rotate_body_matrix(X_B: np.ndarray, axis: object, s: int, rtol: float = 1e-13) -> Series:
    """Exact Fourier coefficients of ``Rt(t) X_B Rt(t)^T``.

    Parameters
    ----------
    X_B
        Body-frame matrix over ``n`` 3-vector blocks (shape ``3n x 3n``; a 6-DOF node is two
        blocks). Body axes coincide with the global axes at ``t = 0``.
    axis, s
        Spin axis and spin harmonic (``W = s * w1``).
    rtol
        Coefficients below ``rtol`` times the largest are dropped (an axisymmetric ``X_B`` gives
        only harmonic 0).

    Returns
    -------
    dict
        Keys from ``{0, +-s, +-2s}``; harmonic 0 real.

    Examples
    --------
    A stiffness 2 along x and 1 along y, spinning about z, seen in the inertial frame:

    >>> K = rotate_body_matrix(np.diag([2.0, 1.0, 0.0]), [0, 0, 1], 1)
    >>> sorted(K), K[0][:2, :2]
    ([-2, 0, 2], array([[1.5, 0. ], [0. , 1.5]]))
    """
    X = np.asarray(X_B)
    _blocks(X, "X_B")
    R = rotation_series(axis, s)
    return clean_series(_sandwich(R, X, R), rtol)


def rotate_body_vector(v_B: np.ndarray, axis: object, s: int, rtol: float = 1e-13) -> Series:
    """Exact Fourier coefficients of ``Rt(t) v_B`` for a body-frame vector over 3-blocks.

    >>> v = rotate_body_vector(np.array([1.0, 0.0, 0.0]), [0, 0, 1], 1)
    >>> sorted(v), v[1]
    ([-1, 0, 1], array([0.5+0.j , 0. -0.5j, 0. +0.j ]))
    """
    v = np.asarray(v_B).reshape(-1)
    if v.size % 3:
        raise ModelError(f"`v_B` must have a length that is a multiple of 3, got {v.size}")
    R = rotation_series(axis, s)
    n = v.size // 3
    out = {k: np.einsum("ab,ib->ia", P, v.reshape(n, 3)).reshape(-1) for k, P in R.items()}
    return clean_series(out, rtol)


def circulatory_matrix(
    D_B: np.ndarray, axis: object, s: int, w1: float, rtol: float = 1e-13
) -> Series:
    """Exact Fourier coefficients of the circulatory stiffness ``Rt D_B (Rt')^T``.

    Material (rotating) damping acts on the deformation rate in the body frame,
    ``d/dt(Rt^T q) = Rt^T q' + (Rt')^T q``; hence ``D += Rt D_B Rt^T`` and
    ``K += Rt D_B (Rt')^T`` (this function).

    Examples
    --------
    Isotropic rotating damping ``c_r`` about z gives ``c_r W [[0, 1], [-1, 0]]``:

    >>> Kc = circulatory_matrix(np.diag([0.5, 0.5, 0.0]), [0, 0, 1], 2, 10.0)
    >>> Kc[0][:2, :2]
    array([[  0.,  10.],
           [-10.,   0.]])
    """
    X = np.asarray(D_B)
    _blocks(X, "D_B")
    if not np.isfinite(w1):
        raise ModelError(f"`w1` must be finite, got {w1!r}")
    R = rotation_series(axis, s)
    dR = derivative(R, w1)
    if not dR:
        return {0: np.zeros_like(X, dtype=float)}
    return clean_series(_sandwich(R, X, dR), rtol)
