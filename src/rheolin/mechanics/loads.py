"""External loads: gravity and harmonic forces/moments at nodes.

Unbalance loads come from the rigid nodes (:mod:`rheolin.mechanics.rigid`); the static
transmission error from the gear meshes (:mod:`rheolin.mechanics.gears`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from ..errors import ModelError
from ._term import Term
from .joints import lever

__all__ = [
    "gravity_load",
    "gravity_vector",
    "harmonic_force_term",
    "moment_at_node",
    "torque_value",
]


def gravity_vector(gravity: ArrayLike) -> np.ndarray:
    """Gravity [m/s^2] as a finite 3-vector (global axes).

    >>> gravity_vector([0, -9.81, 0]).tolist()
    [0.0, -9.81, 0.0]
    """
    g = np.asarray(gravity, dtype=float).reshape(-1)
    if g.shape != (3,) or not np.all(np.isfinite(g)):
        raise ModelError(f"`gravity` must be a finite 3-vector [m/s^2], got {gravity!r}")
    return g


def moment_at_node(
    force: Sequence[float], moment: Sequence[float], offset: Sequence[float] | None
) -> Sequence[float]:
    """The moment a node carries for a force acting at ``offset`` [m] from it, rigidly
    attached: ``moment + r x F`` (``moment`` itself without an offset).

    >>> [float(x) for x in moment_at_node((0.0, 10.0, 0.0), (0.0, 0.0, 0.0), (0.5, 0.0, 0.0))]
    [0.0, 0.0, 5.0]
    """
    T = lever(offset)
    if T is None:
        return moment
    # F at r: the node's load is T^T (F, M) = (F, M + r x F)
    return list(T.T @ np.concatenate([np.asarray(force, float), np.asarray(moment, float)]))[3:]


def torque_value(torque: float | str) -> float | str:
    """A static torque [N m]: a finite number, or ``"reaction"`` (the torque that balances
    the others, found with the operating point).

    >>> torque_value(3), torque_value("reaction")
    (3.0, 'reaction')
    """
    if isinstance(torque, str):
        if torque != "reaction":
            raise ModelError(f"`torque` must be a number [N m] or 'reaction', got {torque!r}")
        return torque
    try:
        value = float(torque)
    except (TypeError, ValueError):
        raise ModelError(f"`torque` must be a number [N m] or 'reaction', got {torque!r}") from None
    if not np.isfinite(value):
        raise ModelError(f"`torque` must be finite, got {value!r}")
    return value


def gravity_load(
    M: Mapping[int, sp.sparray | np.ndarray], gravity: ArrayLike, n_nodes: int
) -> dict[int, np.ndarray]:
    """Load of a uniform gravity field: ``f_k = M_k g`` with ``g`` on every node's translations.

    This is exact for every inertia term: a rigid node gets ``m g`` and the moment
    ``m c(t) x g`` of its (rotating) centre-of-mass offset; a beam gets its consistent loads.

    Parameters
    ----------
    M
        Mass matrix coefficients of the assembled model.
    gravity
        Acceleration of gravity [m/s^2] in global axes, e.g. ``(0, -9.81, 0)``.
    n_nodes
        Number of nodes (6 DOFs each).

    Examples
    --------
    >>> f = gravity_load({0: np.diag([2.0] * 6)}, (0.0, -9.81, 0.0), 1)
    >>> f[0]
    array([  0.  , -19.62,   0.  ,   0.  ,   0.  ,   0.  ])
    """
    g = gravity_vector(gravity)
    field = np.tile(np.concatenate([g, np.zeros(3)]), n_nodes)
    out: dict[int, np.ndarray] = {}
    for k, Mk in M.items():
        if Mk.shape[1] > field.size:  # modal DOFs (condensed bodies) after the nodes: 0
            field = np.concatenate([field, np.zeros(Mk.shape[1] - field.size)])
        v = Mk @ field
        v = np.real(v) if k == 0 else np.asarray(v, dtype=complex)
        if np.any(v != 0):
            out[int(k)] = v
    return out


def harmonic_force_term(
    dofs: ArrayLike,
    force: ArrayLike = (0.0, 0.0, 0.0),
    moment: ArrayLike = (0.0, 0.0, 0.0),
    harmonic: int = 0,
    phase: float = 0.0,
) -> Term:
    """A force/moment fixed in direction, ``F(t) = F cos(n w1 t + phase)`` at one node.

    Parameters
    ----------
    dofs
        The node's six global DOFs.
    force, moment
        Amplitude vectors [N], [N m] in global axes.
    harmonic
        ``n``: frequency in units of ``w1``; 0 is a static load ``F cos(phase)``.
    phase
        Phase [rad].

    Examples
    --------
    >>> t = harmonic_force_term(range(6), force=(10.0, 0, 0), harmonic=3)
    >>> t.f[3][:2], t.f[-3][:2]
    (array([5.+0.j, 0.+0.j]), array([5.-0.j, 0.-0.j]))
    """
    vec = np.concatenate([np.asarray(force, float).ravel(), np.asarray(moment, float).ravel()])
    if vec.shape != (6,) or not np.all(np.isfinite(vec)):
        raise ModelError("`force` and `moment` must be finite 3-vectors [N], [N m]")
    if isinstance(harmonic, bool) or not isinstance(harmonic, int | np.integer):
        raise ModelError(f"`harmonic` must be an integer, got {harmonic!r}")
    n = abs(int(harmonic))
    if n == 0:
        f = {0: vec * np.cos(phase)}
    else:
        c = vec * np.exp(1j * phase) / 2
        f = {n: c, -n: np.conj(c)}
    return Term(np.asarray(dofs, dtype=np.int64), f=f)
