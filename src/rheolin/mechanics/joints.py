"""Joints: bearings and couplings between a node and ground or between two nodes.

A joint acts on the *relative* displacement ``r = q_a - q_b`` of two nodes (``q_b = 0`` for
ground) through a 6x6 stiffness ``K_J`` and damping ``D_J`` over ``(ux, uy, uz, phix, phiy,
phiz)``. Its contribution to the node pair is ``[[X, -X], [-X, X]]``.

* In the inertial frame (bearings, housings): constant, harmonic 0 only.
* In the axes of a body spinning at ``W = s w1`` about ``e`` (docs/rotating-bodies.md):
  ``K(t) += R K_J R^T`` and, for damping acting on the body-frame rate,
  ``D(t) += R D_J R^T``, ``K(t) += R D_J R'^T`` with ``R = blockdiag(R(t), R(t))``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ModelError
from ._term import SpeedTerm, Term
from .bearing_table import SpeedTable
from .rotation import circulatory_matrix, rotate_body_matrix

__all__ = [
    "COMPONENTS",
    "bearing_record",
    "coupling_speed_term",
    "coupling_term",
    "expand_matrix",
    "joint_term",
    "lever",
    "link_components",
    "pair_block",
]

#: Names of the six DOFs of a node, in order.
COMPONENTS = ("ux", "uy", "uz", "phix", "phiy", "phiz")


def expand_matrix(
    matrix: object, components: Sequence[str] | None = None, field: str = "stiffness"
) -> np.ndarray:
    """Embed a joint matrix given on some node components into a 6x6 matrix.

    Parameters
    ----------
    matrix
        Scalar (isotropic on ``components``), vector (diagonal) or square matrix.
    components
        Names from :data:`COMPONENTS` that the rows/columns refer to; default all six
        for a 6x6 matrix.
    field
        Name used in error messages.

    Examples
    --------
    Anisotropic radial bearing with cross-coupling:

    >>> K = expand_matrix([[1e8, 2e7], [-2e7, 2e8]], ["ux", "uy"])
    >>> K[:2, :2], bool(K[2:].any())
    (array([[ 1.e+08,  2.e+07],
           [-2.e+07,  2.e+08]]), False)
    """
    if components is None:
        components = COMPONENTS
    components = list(components)
    bad = [c for c in components if c not in COMPONENTS]
    if bad or len(set(components)) != len(components):
        raise ModelError(
            f"`components` must be distinct names from {list(COMPONENTS)}, got {components}"
        )
    n = len(components)
    a = np.asarray(matrix, dtype=float)
    if a.ndim == 0:
        a = float(a) * np.eye(n)
    elif a.ndim == 1:
        if a.size != n:
            raise ModelError(f"`{field}` has {a.size} entries but `components` has {n}")
        a = np.diag(a)
    if a.shape != (n, n):
        raise ModelError(
            f"`{field}` must be a scalar, a length-{n} vector or {n}x{n}, got {a.shape}"
        )
    if not np.all(np.isfinite(a)):
        raise ModelError(f"`{field}` contains NaN or inf")
    idx = [COMPONENTS.index(c) for c in components]
    out = np.zeros((6, 6))
    out[np.ix_(idx, idx)] = a
    return out


def lever(offset: ArrayLike | None) -> np.ndarray | None:
    """``T`` (6x6): the motion ``(u + phi x r, phi)`` of a point at ``offset`` ``r`` from a
    node, rigidly attached to it, from the node's ``(u, phi)`` (None: no offset).

    >>> lever([0.0, 0.0, 0.5]) @ [0, 0, 0, 1.0, 0, 0]  # a tilt about x moves the point in -y
    array([ 0. , -0.5,  0. ,  1. ,  0. ,  0. ])
    """
    if offset is None:
        return None
    r = np.asarray(offset, dtype=float).ravel()
    if r.shape != (3,) or not np.all(np.isfinite(r)):
        raise ModelError(f"`offset` must be a finite 3-vector [m], got {offset!r}")
    if not np.any(r):
        return None
    T = np.eye(6)
    T[:3, 3:] = -np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    return T


def pair_block(
    x: np.ndarray, two: bool, levers: tuple[np.ndarray | None, np.ndarray | None] = (None, None)
) -> np.ndarray:
    """A 6x6 joint matrix on the relative motion of its two attachment points, on the DOFs of
    its node (``two=False``: to ground) or of both nodes: ``[[Ta^T x Ta, -Ta^T x Tb],
    [-Tb^T x Ta, Tb^T x Tb]]`` with the :func:`lever` of each side (identity without one)."""
    Ta, Tb = (np.eye(6) if t is None else t for t in levers)
    if not two:
        return x if levers[0] is None else Ta.T @ x @ Ta
    if levers == (None, None):
        return np.block([[x, -x], [-x, x]])
    return np.block([[Ta.T @ x @ Ta, -Ta.T @ x @ Tb], [-Tb.T @ x @ Ta, Tb.T @ x @ Tb]])


def _pair(
    dofs_a: ArrayLike,
    dofs_b: ArrayLike | None,
    X: dict[int, np.ndarray],
    levers: tuple[np.ndarray | None, np.ndarray | None] = (None, None),
) -> tuple[np.ndarray, dict[int, np.ndarray]]:
    if dofs_b is None:
        return np.asarray(dofs_a, dtype=np.int64), {
            k: pair_block(x, False, levers) for k, x in X.items()
        }
    dofs = np.concatenate([np.asarray(dofs_a), np.asarray(dofs_b)]).astype(np.int64)
    return dofs, {k: pair_block(x, True, levers) for k, x in X.items()}


def joint_term(
    dofs_a: ArrayLike,
    dofs_b: ArrayLike | None = None,
    stiffness: np.ndarray | None = None,
    damping: np.ndarray | None = None,
) -> Term:
    """A joint fixed in the inertial frame (bearing), node-to-ground or node-to-node.

    Parameters
    ----------
    dofs_a, dofs_b
        The six global DOFs of each node; ``dofs_b=None`` means ground.
    stiffness, damping
        6x6 matrices on the relative displacement ``q_a - q_b`` (see :func:`expand_matrix`).

    Examples
    --------
    >>> K = expand_matrix(1e6, ["ux"])
    >>> t = joint_term(range(6), range(6, 12), stiffness=K)
    >>> t.K[0][0, [0, 6]]
    array([ 1000000., -1000000.])
    """
    X = {0: np.zeros((6, 6)) if stiffness is None else np.asarray(stiffness, float)}
    C = {0: np.zeros((6, 6)) if damping is None else np.asarray(damping, float)}
    dofs, K = _pair(dofs_a, dofs_b, X)
    _, D = _pair(dofs_a, dofs_b, C)
    return Term(dofs, K=K if stiffness is not None else {}, D=D if damping is not None else {})


def coupling_term(
    dofs_a: ArrayLike,
    dofs_b: ArrayLike | None,
    stiffness: np.ndarray | None = None,
    damping: np.ndarray | None = None,
    spin: int = 0,
    axis: ArrayLike = (0.0, 0.0, 1.0),
    omega: float = 1.0,
) -> Term:
    """A joint whose stiffness/damping are given in the axes of a body spinning at ``s w1``.

    ``spin = 0`` gives the inertial-frame joint of :func:`joint_term`.

    Examples
    --------
    An elastic coupling, stiffer along its own x axis, rotating at ``w1``:

    >>> t = coupling_term(range(6), None, stiffness=expand_matrix([3.0, 1.0], ["ux", "uy"]),
    ...                   spin=1, omega=10.0)
    >>> sorted(t.K), complex(np.round(t.K[2][0, 0], 12))
    ([-2, 0, 2], (0.5+0j))
    """
    return coupling_speed_term((dofs_a, dofs_b), stiffness, damping, spin, axis).at(omega)


def coupling_speed_term(
    nodes: tuple[ArrayLike, ArrayLike | None],
    stiffness: np.ndarray | None,
    damping: np.ndarray | None,
    spin: int = 0,
    axis: ArrayLike = (0.0, 0.0, 1.0),
    mass: np.ndarray | None = None,
    levers: tuple[np.ndarray | None, np.ndarray | None] = (None, None),
) -> SpeedTerm:
    """:func:`coupling_term` as a polynomial in ``w1``: the circulatory stiffness of the
    rotating damping ``Rt C Rt'^T`` is its linear part, the rest is constant.

    ``nodes`` holds the DOFs of both nodes (``None``: ground); ``mass`` is an added mass on
    the relative acceleration (seals, squeeze films), in the same axes as the stiffness;
    ``levers`` the :func:`lever` of each side when the joint acts at points offset from the
    nodes (inertial-frame joints).

    >>> t = coupling_speed_term((range(6), None), None, expand_matrix(2.0, ["ux", "uy"]), spin=1)
    >>> sorted(t.K), t.K[1][0][:2, :2] + 0.0
    ([1], array([[ 0.,  2.], [-2.,  0.]]))
    """
    dofs_a, dofs_b = nodes
    if isinstance(spin, bool) or not isinstance(spin, int | np.integer):
        raise ModelError(f"`spin` must be an integer harmonic, got {spin!r}")
    K: dict[int, dict[int, np.ndarray]] = {}
    D: dict[int, dict[int, np.ndarray]] = {}
    M: dict[int, dict[int, np.ndarray]] = {}
    s = int(spin)
    if mass is not None and np.any(mass):
        M[0] = rotate_body_matrix(np.asarray(mass, float), axis, s)
    if stiffness is not None:
        K[0] = rotate_body_matrix(np.asarray(stiffness, float), axis, s)
    if damping is not None:
        C = np.asarray(damping, float)
        D[0] = rotate_body_matrix(C, axis, s)
        if s != 0:
            K[1] = circulatory_matrix(C, axis, s, 1.0)
    dofs, _ = _pair(dofs_a, dofs_b, {})
    for X in (K, D, M):
        for p in X:
            X[p] = _pair(dofs_a, dofs_b, X[p], levers)[1]
    return SpeedTerm(dofs, M=M, K=K, D=D)


# --------------------------------------------------------------------------- model input
def _per_speed(value: Any, n: int, components: Sequence[str] | None, name: str) -> np.ndarray:
    """One 6x6 matrix per speed from a table (or one value for every speed)."""
    a = np.asarray(value, dtype=float)
    if a.ndim == 0:
        return np.array([expand_matrix(float(a), components, name)] * n)
    if a.shape[0] != n:
        raise ModelError(f"`{name}`: give one entry per speed ({n}), got {a.shape[0]}")
    return np.array([expand_matrix(x, components, f"{name}[{i}]") for i, x in enumerate(a)])


def _preload(preload: ArrayLike | None, frame: str | None, speeds: object) -> np.ndarray | None:
    """The preload as 6 numbers (force, moment), for constant inertial-frame joints only."""
    if preload is None:
        return None
    pre = np.asarray(preload, dtype=float).ravel()
    if pre.size not in (3, 6) or not np.all(np.isfinite(pre)):
        raise ModelError(
            f"`preload` must be 3 (force) or 6 (force, moment) finite numbers, got {preload!r}"
        )
    if frame is not None or speeds is not None:
        raise ModelError("`preload`: only for constant joints in the inertial frame")
    return np.concatenate([pre, np.zeros(6 - pre.size)])


def bearing_record(
    stiffness: Any,
    damping: Any,
    mass: Any,
    components: Sequence[str] | None,
    frame: str | None,
    speeds: Sequence[float] | None,
    interpolation: str,
    extrapolate: bool,
    offset: Sequence[float] | None,
    other_offset: Sequence[float] | None,
    two_sided: bool,
    preload: Sequence[float] | None,
) -> dict[str, Any]:
    """The matrices (or speed table), frame, offsets and preload of a bearing, checked, as
    the model's joint table holds them (``Model.add_bearing`` names the arguments).

    >>> j = bearing_record(1e6, 0.0, 0.0, ["ux"], None, None, "cubic", False, None, None,
    ...                    False, [0.0, 5.0, 0.0])
    >>> float(j["K"][0, 0]), j["preload"].tolist()
    (1000000.0, [0.0, 5.0, 0.0, 0.0, 0.0, 0.0])
    """
    if frame is not None and (offset is not None or other_offset is not None):
        raise ModelError("`offset`: only for joints in the inertial frame (frame=None)")
    if other_offset is not None and not two_sided:
        raise ModelError("`other_offset` needs `other_body` (a joint to ground has one side)")
    lever(offset)  # checked: a finite 3-vector
    lever(other_offset)
    pre = _preload(preload, frame, speeds)
    table = None
    if speeds is None:
        K = expand_matrix(stiffness, components, "stiffness")
        D = expand_matrix(damping, components, "damping")
        M = expand_matrix(mass, components, "mass")
    else:
        if frame is not None:
            raise ModelError("`speeds`: speed-dependent coefficients need `frame=None`")
        n = np.asarray(speeds, dtype=float).size
        tabs = [
            _per_speed(x, n, components, fld)
            for x, fld in ((stiffness, "stiffness"), (damping, "damping"), (mass, "mass"))
        ]
        table = SpeedTable(speeds, tabs[0], tabs[1], tabs[2], interpolation, bool(extrapolate))
        K, D, M = (np.zeros((6, 6)) for _ in range(3))
    return dict(
        K=K,
        D=D,
        M=M,
        frame=frame,
        table=table,
        components=None if components is None else list(components),
        offset=None if offset is None else [float(v) for v in offset],
        other_offset=None if other_offset is None else [float(v) for v in other_offset],
        preload=pre,
    )


def link_components(components: Sequence[str] | None) -> list[str]:
    """The components a rigid link constrains: distinct names from :data:`COMPONENTS`, all six
    when None."""
    comps = list(COMPONENTS) if components is None else list(components)
    bad = [c for c in comps if c not in COMPONENTS]
    if bad or not comps or len(set(comps)) != len(comps):
        raise ModelError(
            f"`components` must be distinct names from {list(COMPONENTS)}, got {components!r}"
        )
    return comps
