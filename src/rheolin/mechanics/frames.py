"""Writing some DOFs in a rotating frame: an exact periodic change of coordinates.

A frame turning at ``W = s w1`` about ``e`` (a planetary set's carrier) has the rotation
``R(t) = P0 + P+ exp(i W t) + P- exp(-i W t)`` (docs/rotating-bodies.md). Writing the DOF
3-blocks of some nodes in its axes, ``q = T(t) z`` with ``T = R`` on those blocks and the
identity elsewhere, turns ``M q'' + D q' + K q = f`` (projected on ``T^T``) into

    M~ = T^T M T,   D~ = T^T (D T + 2 M T'),   K~ = T^T (K T + D T' + M T''),   f~ = T^T f,

a finite Fourier series again (harmonics shifted by at most ``+-2s``), nothing sampled. The
Floquet exponents are those of the original system (``T`` is periodic and the identity at
``t = 0``), the steady state is the same motion written in the other axes.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ModelError
from ._term import SpeedTerm
from .rotation import add_series, clean_series, derivative, rotation_series, series_product

__all__ = ["frame_rotation", "frame_vector", "in_frame", "inertial_rows", "sandwich", "transpose"]

Series = dict[int, np.ndarray]


def transpose(series: Series) -> Series:
    """The series of ``X(t)^T`` (``X`` real).

    >>> transpose({1: np.array([[0, 1j], [0, 0]])})[1].tolist()
    [[0j, 0j], [1j, 0j]]
    """
    return {k: np.asarray(v).T for k, v in series.items()}


def sandwich(Q: Series, X: Series, right: Series | None = None) -> Series:
    """``Q^T X Q`` (or ``Q^T X right``) as an exact convolution.

    >>> sorted(sandwich({1: np.eye(1), -1: np.eye(1)}, {0: np.eye(1)}))
    [-2, 0, 2]
    """
    return series_product(series_product(transpose(Q), X), Q if right is None else right)


def frame_rotation(
    dofs: ArrayLike, rotated: set[int] | frozenset[int], axis: object, spin: int
) -> Series:
    """Series of ``T(t)``, ``q_inertial = T z`` on a term's DOFs: ``R(t)`` on every 3-block
    ``(3b, 3b+1, 3b+2)`` of global DOFs whose block ``b`` is in ``rotated``, the identity on
    the others (modal DOFs, inertial nodes).

    >>> T = frame_rotation([0, 1, 2, 3, 4, 5, 6], {0}, [0, 0, 1], 1)
    >>> sorted(T), T[0][6, 6].real, T[1][0, 1]
    ([-1, 0, 1], np.float64(1.0), np.complex128(0.5j))
    """
    d = np.asarray(dofs, dtype=np.int64).ravel()
    R = rotation_series(axis, spin)
    out: Series = {k: np.zeros((d.size, d.size), dtype=complex) for k in R}
    out[0] = out.get(0, np.zeros((d.size, d.size), dtype=complex))
    where = {int(g): i for i, g in enumerate(d)}
    done: set[int] = set()
    for i, g in enumerate(d):
        b = int(g) // 3
        if b not in rotated:
            out[0][i, i] += 1.0
            continue
        if b in done:
            continue
        done.add(b)
        try:
            local = [where[3 * b + c] for c in range(3)]
        except KeyError:
            raise ModelError(
                f"a term holds only part of the 3-vector at DOFs {3 * b}..{3 * b + 2}; it "
                "cannot be turned into the carrier's frame"
            ) from None
        for k, P in R.items():
            out[k][np.ix_(local, local)] += P
    return out


def in_frame(
    term: SpeedTerm, rotated: set[int] | frozenset[int], axis: object, spin: int
) -> SpeedTerm:
    """A speed term with the DOF 3-blocks ``rotated`` written in the axes of a frame spinning
    at ``spin * w1`` about ``axis``.

    With ``q = T(t) z`` (:func:`frame_rotation`) the equations, projected on ``T^T``, become
    ``M~ = T^T M T``, ``D~ = T^T (D T + 2 M T')``, ``K~ = T^T (K T + D T' + M T'')``,
    ``f~ = T^T f``. ``T'`` is linear in ``w1`` and ``T''`` quadratic, so each power of ``w1``
    maps to one power: ``D^(p) T'`` joins ``K^(p+1)``, ``M T'`` joins ``D^(1)`` and ``M T''``
    joins ``K^(2)``. A term touching no rotated block is returned as it is.

    Examples
    --------
    A mass on an isotropic spring to ground, seen from axes turning at ``W``: Coriolis
    ``2 m W [e]x`` and centripetal ``-m W^2`` appear, the spring stays.

    >>> t = SpeedTerm(np.arange(3), M={0: {0: np.eye(3)}}, K={0: {0: 4 * np.eye(3)}})
    >>> c = in_frame(t, {0}, [0, 0, 1], 1).at(2.0)
    >>> c.D[0][:2, :2].real + 0.0, np.diag(c.K[0]).real
    (array([[ 0., -4.], [ 4.,  0.]]), array([0., 0., 4.]))
    """
    d = np.asarray(term.dofs, dtype=np.int64).ravel()
    if not any(int(g) // 3 in rotated for g in d):
        return term
    T = frame_rotation(d, rotated, axis, spin)
    dT, ddT = derivative(T, 1.0), derivative(T, 1.0, 2)
    M, D, K, f = term.M, term.D, term.K, term.f
    if any(p != 0 for p in M):
        raise ModelError("a mass that depends on the speed cannot be turned into a frame")
    out = SpeedTerm(term.dofs)
    for p, X in M.items():
        out.M[p] = clean_series(sandwich(T, X))
        if dT:
            _accumulate(out.D, 1, {k: 2 * v for k, v in sandwich(T, X, dT).items()})
            _accumulate(out.K, 2, sandwich(T, X, ddT))
    for p, X in D.items():
        _accumulate(out.D, p, sandwich(T, X))
        if dT:
            _accumulate(out.K, p + 1, sandwich(T, X, dT))
    for p, X in K.items():
        _accumulate(out.K, p, sandwich(T, X))
    for p, v in f.items():
        out.f[p] = clean_series(series_product(transpose(T), v, np.matmul))
    for table in (out.D, out.K):
        for p in list(table):
            table[p] = clean_series(table[p])
    if max(out.K, default=0) > 2:
        raise ModelError("a term's stiffness would be of power > 2 in the speed")
    return out


def inertial_rows(
    term: SpeedTerm, rotated: set[int] | frozenset[int], axis: object, spin: int
) -> SpeedTerm:
    """An element's force in global axes from DOFs some of which are in the carrier's axes:
    the columns turned (``K T + D T'``, ``D T``), the rows left inertial. For outputs (a
    bearing's force on its support in global axes); ``M`` is left out.

    >>> t = SpeedTerm(np.arange(3), K={0: {0: np.eye(3)}}, D={0: {0: np.eye(3)}})
    >>> r = inertial_rows(t, {0}, [0, 0, 1], 1).at(1.0)
    >>> complex(r.K[1][0, 1]), complex(r.K[0][2, 2])
    ((-0.5+0.5j), (1+0j))
    """
    d = np.asarray(term.dofs, dtype=np.int64).ravel()
    if not any(int(g) // 3 in rotated for g in d):
        return term
    T = frame_rotation(d, rotated, axis, spin)
    dT = derivative(T, 1.0)
    out = SpeedTerm(term.dofs, f=dict(term.f))
    for p, X in term.K.items():
        _accumulate(out.K, p, series_product(X, T))
    for p, X in term.D.items():
        _accumulate(out.D, p, series_product(X, T))
        if dT:
            _accumulate(out.K, p + 1, series_product(X, dT))
    for table in (out.D, out.K):
        for p in list(table):
            table[p] = clean_series(table[p])
    return out


def frame_vector(
    w: np.ndarray, dofs: ArrayLike, rotated: set[int] | frozenset[int], axis: object, spin: int
) -> Series:
    """The series ``g(t) = T(t)^T w``: a deflection ``delta = w^T q`` of inertial DOFs
    written on DOFs some of which are in the carrier's axes, ``delta(t) = g(t)^T z``.

    >>> g = frame_vector(np.array([1.0, 0.0, 0.0]), [0, 1, 2], {0}, [0, 0, 1], 1)
    >>> sorted(g), complex(g[1][1])
    ([-1, 1], 0.5j)
    """
    T = frame_rotation(dofs, rotated, axis, spin)
    v = np.asarray(w).ravel()
    return {k: X.T @ v for k, X in T.items() if np.any(X.T @ v)}


def _accumulate(table: dict[int, Series], power: int, series: Series) -> None:
    table[power] = add_series(table.get(power, {}), series)
