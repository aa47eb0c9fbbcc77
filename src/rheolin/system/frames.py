"""Rotating bodies written in their own frames: an exact change of coordinates of a periodic
system (docs/stability.md, large models).

A body spinning at ``W = s w1`` about the unit axis ``e`` turns its nodes' translation and
rotation triples by ``R(t) = P0 + P+ e^{i W t} + P- e^{-i W t}`` (docs/rotating-bodies.md).
With ``q = T(t) p``, ``T`` that rotation on the chosen bodies' triples and the identity
elsewhere, the system in ``p`` is

    M~ = T^T M T,   D~ = T^T (2 M T' + D T),   K~ = T^T (M T'' + D T' + K T),

again periodic with period ``2 pi / w1`` (``T`` is): the same Floquet multipliers, exponents
moved by multiples of ``i w1``. In its own frame a shaft's stiffness, material damping and
inertia are constant; what varies are its joints to the inertial frame.

>>> import numpy as np
>>> from rheolin.system import PeriodicSystem
>>> k = np.diag([1.0, 2.0, 5.0])  # stiffer in y than in x, body axes
>>> sym, dif = (k[0, 0] + k[1, 1]) / 2, (k[0, 0] - k[1, 1]) / 2
>>> K2 = dif / 2 * np.array([[1, -1j, 0], [-1j, -1, 0], [0, 0, 0]])  # k(t) = R k R^T
>>> s = PeriodicSystem(1.0, M={0: np.eye(3)}, K={0: np.diag([sym, sym, 5.0]), 2: K2})
>>> frame = BodyFrame("shaft", 1, (0.0, 0.0, 1.0), np.array([[0, 1, 2]]))
>>> p = rotate(s, [frame])
>>> np.round(p.K[0].toarray().real, 12)  # body-axes stiffness, centrifugal softening
array([[0., 0., 0.],
       [0., 1., 0.],
       [0., 0., 5.]])
>>> p.coefficient_harmonics  # a free body has nothing left that varies
[]
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .periodic import PeriodicSystem

__all__ = ["BodyFrame", "rotate"]

#: Entries below this fraction of the largest in their matrix are rounding of the products.
ROUNDING = 1e-13


@dataclass(frozen=True)
class BodyFrame:
    """A rotating body's frame: its name, spin harmonic ``s`` (``W = s w1``), unit axis and
    the DOF triples it turns (``(m, 3)``: ``ux uy uz`` and ``phix phiy phiz`` of every node).

    ``meshed``: a gear mesh acts on the body (its mean stiffness would vary in the body's
    frame); ``distributed``: the body's own coefficients vary in time on its inner nodes (a
    non-axisymmetric section).
    """

    name: str
    spin: int
    axis: tuple[float, float, float]
    triples: np.ndarray
    meshed: bool = False
    distributed: bool = False


def _rotation(axis: Sequence[float], s: int) -> dict[int, np.ndarray]:
    e = np.asarray(axis, dtype=float)
    e = e / np.linalg.norm(e)
    P0 = np.outer(e, e)
    ex = np.array([[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]])
    Pp = 0.5 * (np.eye(3) - P0 - 1j * ex)
    if s == 0:
        return {0: np.eye(3)}
    return {0: P0, s: Pp, -s: Pp.conj()}


def transformation(n: int, frames: Iterable[BodyFrame]) -> dict[int, sp.csr_array]:
    """``T(t)`` as Fourier coefficients (sparse ``n x n``): the frames' rotations on their
    triples, the identity on every other DOF."""
    rows: dict[int, list[np.ndarray]] = {}
    cols: dict[int, list[np.ndarray]] = {}
    vals: dict[int, list[np.ndarray]] = {}
    turned = np.zeros(n, dtype=bool)
    for f in frames:
        tri = np.asarray(f.triples, dtype=np.int64).reshape(-1, 3)
        turned[tri.ravel()] = True
        for k, P in _rotation(f.axis, f.spin).items():
            r, c = np.nonzero(np.abs(P) > 0)
            rows.setdefault(k, []).append(tri[:, r].ravel())
            cols.setdefault(k, []).append(tri[:, c].ravel())
            vals.setdefault(k, []).append(np.tile(P[r, c], tri.shape[0]))
    keep = np.flatnonzero(~turned)
    rows.setdefault(0, []).append(keep)
    cols.setdefault(0, []).append(keep)
    vals.setdefault(0, []).append(np.ones(keep.size))
    return {
        k: sp.csr_array(
            (np.concatenate(vals[k]), (np.concatenate(rows[k]), np.concatenate(cols[k]))),
            shape=(n, n),
        )
        for k in rows
    }


def _product(X: dict[int, sp.csr_array], Y: dict[int, sp.csr_array]) -> dict[int, sp.csr_array]:
    out: dict[int, sp.csr_array] = {}
    for i, x in X.items():
        for j, y in Y.items():
            z = sp.csr_array(x @ y)
            out[i + j] = out[i + j] + z if i + j in out else z
    return out


def _sum(*terms: dict[int, sp.csr_array]) -> dict[int, sp.csr_array]:
    out: dict[int, sp.csr_array] = {}
    for t in terms:
        for k, v in t.items():
            out[k] = out[k] + v if k in out else v
    return out


def _clean(X: dict[int, sp.csr_array]) -> dict[int, sp.csr_array]:
    """Drop the rounding of the products; harmonic 0 real when the input was."""
    top = max((float(abs(v).max()) for v in X.values() if v.nnz), default=0.0)
    out: dict[int, sp.csr_array] = {}
    for k, v in X.items():
        v = sp.csr_array(v)
        v.data[np.abs(v.data) <= ROUNDING * top] = 0
        v.eliminate_zeros()
        if k == 0 and v.nnz and np.abs(v.data.imag).max() <= ROUNDING * top:
            v = sp.csr_array(v.real)
        if v.nnz:
            out[k] = v
    return out


def rotate(system: PeriodicSystem, frames: Iterable[BodyFrame]) -> PeriodicSystem:
    """The homogeneous system in the coordinates ``p`` of ``q = T(t) p`` (module docstring):
    the bodies of ``frames`` in their own frames. The loads are not carried over (the result
    is for stability). A frame with spin 0 changes nothing."""
    frames = [f for f in frames if f.spin != 0]
    n, w = system.n, system.omega
    T = transformation(n, frames)
    Tt = {k: sp.csr_array(v.T) for k, v in T.items()}
    dT = {k: (1j * k * w) * v for k, v in T.items() if k}
    ddT = {k: -((k * w) ** 2) * v for k, v in T.items() if k}

    def table(x: dict) -> dict[int, sp.csr_array]:
        return {k: sp.csr_array(v) for k, v in x.items()}

    M, D, K = table(system.M), table(system.D), table(system.K)
    Mt = _product(Tt, _product(M, T))
    Dt = _product(Tt, _sum(_product({k: 2 * v for k, v in M.items()}, dT), _product(D, T)))
    Kt = _product(Tt, _sum(_product(M, ddT), _product(D, dT), _product(K, T)))
    return PeriodicSystem(w, M=_clean(Mt), D=_clean(Dt), K=_clean(Kt))
