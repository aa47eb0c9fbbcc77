"""Planetary sets in the carrier's frame: planets always, the sun, ring and carrier bodies too.

Why the carrier's frame. A planet revolves with the carrier (speed ``W_c``) while it spins on its
pin. Written in the carrier's axes (the global axes at ``t = 0``), as Lin & Parker write the
whole set, a set on isotropic supports is time-invariant but for its mesh stiffness: its
inertia, bearings and mesh geometry are constant, the static deflection under torque (load
sharing, a pin error, the centrifugal load) is static, and the time-averaged system that modes,
Campbell diagrams, the static equilibrium and the Floquet search start from has Lin & Parker's
rotational, translational and planet modes exactly. Written inertially, every coupling of a
planet to the sun, ring and carrier turns at ``+-W_c``; its average drops the central members'
translations from the planets, and the lattice search, which looks for exponents near the
averaged modes, misses the translational ones. So rheolin writes the planets in the carrier's
axes, and the bodies carrying the sun, ring and carrier too (:mod:`rheolin.mechanics.frames`
turns any element's terms, exactly); what is left periodic is where the set meets the inertial
world (an anisotropic support, a parallel mesh on the sun shaft), with the few harmonics
``0, +-W_c, +-2 W_c`` of the carrier's rotation ``R(t) = P0 + P+ exp(i W_c t) + P- exp(-i W_c
t)`` (docs/rotating-bodies.md) times the mesh harmonics, exact and unsampled. A member that
cannot be in this frame (it belongs to another set's frame) stays coupled through ``R(t)``.

A member node whose axes turn relative to the carrier's at ``s w1`` (inertial: ``s = s_c``; in
the carrier's frame: ``s = 0``) has its DOFs ``q_m`` appear in the carrier's axes as
``R6(t)^T q_m`` (``R6 = diag(R, R)``, the relative rotation). An element written in the
carrier's axes on (member, planet) with the constant matrices ``X`` and ``C`` therefore acts
through ``Q(t) = diag(R6(t)^T, I6)``::

    K += Q^T X Q + Q^T C Q',     D += Q^T C Q,     f += Q^T v

(damping acts on the rate seen in the carrier, ``d/dt (Q q)``: the circulatory ``Q^T C Q'``
is linear in the speed). A mesh is ``X = k(t) w w^T``, ``C = c w w^T``, ``v = k(t) e(t) w``; a
planet bearing acts on the planet's motion relative to its pin, ``G = [-L(r_pin), I6]``,
``X = G^T K_B G``, ``C = G^T D_B G``, and a pin position error ``epsilon`` loads it with
``v = G^T K_B epsilon``.

A planet's own inertia, and every term of a body written in the carrier's frame, follows from
its inertial terms (docs/rotating-bodies.md; a planet spins at its absolute speed ``W_p``) by
the change of coordinates ``q = R6(t) z`` (:func:`~rheolin.mechanics.frames.in_frame`)::

    M~ = R6^T M R6,   D~ = R6^T (D R6 + 2 M R6'),   K~ = R6^T (K R6 + D R6' + M R6'')

which for an axisymmetric planet are Lin & Parker's constant Coriolis ``2 m W_c [e]x`` and
centripetal ``-m W_c^2 (I - e e^T)`` terms, with the rotation block's
``2 W_c J_d [e]x - W_p J_p [e]x``. The reference motion on the orbit needs the centripetal
force ``m W_c^2 r_c``: it loads the planet bearing outwards (``f``, quadratic in the speed);
gravity turns in the carrier's axes (harmonics ``+-W_c``).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ModelError
from ._term import SpeedTerm
from .frames import in_frame, sandwich, transpose
from .gears import mesh_convolve
from .joints import lever
from .rigid import RigidNode
from .rotation import (
    add_series,
    clean_series,
    derivative,
    rotation_series,
    series_product,
    unit_axis,
)

__all__ = [
    "carried_speed_term",
    "carried_vector",
    "carrier_projection",
    "centripetal_load",
    "planet_bearing_term",
    "planet_inertia_term",
    "planet_mesh_term",
]

Series = dict[int, np.ndarray]


def carrier_projection(axis: object, spin: int) -> Series:
    """Fourier series of ``Q(t) = diag(R6(t)^T, I6)``: a (member, planet) pair's 12 DOFs in
    the carrier's axes, the member's inertial ones turned by the carrier (spin ``s w1``).

    >>> Q = carrier_projection([0, 0, 1], 2)
    >>> sorted(Q), Q[0][6:, 6:].real.tolist() == np.eye(6).tolist()
    ([-2, 0, 2], True)
    """
    R = rotation_series(axis, spin)
    out: Series = {}
    for k, P in R.items():
        q = np.zeros((12, 12), dtype=complex)
        q[:6, :6] = np.kron(np.eye(2), P.T)
        out[k] = q
    out[0] = out.get(0, np.zeros((12, 12), dtype=complex))
    out[0][6:, 6:] += np.eye(6)
    return out


def carried_speed_term(
    member_dofs: ArrayLike,
    planet_dofs: ArrayLike,
    axis: object,
    spin: int,
    stiffness: Mapping[int, np.ndarray],
    damping: np.ndarray | None = None,
    load: Mapping[int, np.ndarray] | None = None,
) -> SpeedTerm:
    """An element written in the carrier's axes on (member, planet), as a speed term.

    Parameters
    ----------
    member_dofs, planet_dofs
        The six global DOFs of the member node (inertial) and of the planet (carrier axes).
    axis, spin
        The carrier's axis and spin harmonic (``W_c = spin * w1``).
    stiffness
        ``{k: X_k}`` (12x12, carrier axes), the stiffness and its harmonics (mesh stiffness).
    damping
        ``C`` (12x12, carrier axes) on the rate seen in the carrier.
    load
        ``{k: v_k}`` (12, carrier axes).

    Examples
    --------
    A spring of 1 N/m between the member's x and the planet's x: in inertial terms it couples
    the planet to the member's ``x cos(W t) + y sin(W t)``.

    >>> X = np.zeros((12, 12)); X[np.ix_([0, 6], [0, 6])] = [[1, -1], [-1, 1]]
    >>> t = carried_speed_term(range(6), range(6, 12), [0, 0, 1], 1, {0: X})
    >>> K = t.K[0]
    >>> complex(K[1][6, 0]), complex(K[1][6, 1]), complex(K[2][0, 0]), complex(K[0][0, 0])
    ((-0.5+0j), 0.5j, (0.25+0j), (0.5+0j))
    """
    dofs = np.concatenate([np.asarray(member_dofs), np.asarray(planet_dofs)]).astype(np.int64)
    if dofs.shape != (12,):
        raise ModelError(f"a carried element needs 6 + 6 DOFs, got {dofs.size}")
    Q = carrier_projection(axis, spin)
    out = SpeedTerm(dofs)
    X = {int(k): np.asarray(v) for k, v in stiffness.items() if np.any(v)}
    if X:
        out.K[0] = clean_series(sandwich(Q, X))
    if damping is not None and np.any(damping):
        C = {0: np.asarray(damping, dtype=float)}
        out.D[0] = clean_series(sandwich(Q, C))
        dQ = derivative(Q, 1.0)
        if dQ:
            out.K[1] = clean_series(sandwich(Q, C, dQ))
    if load:
        QT = transpose(Q)
        f = series_product(QT, {int(k): np.asarray(v) for k, v in load.items()}, np.matmul)
        out.f[0] = clean_series(f)
    return out


def carried_vector(w: np.ndarray, axis: object, spin: int) -> Series:
    """The series of ``Q(t)^T w``: ``delta(t) = sum_k g_k^T q exp(i k w1 t)`` for a mesh
    vector ``w`` written in the carrier's axes over (member, planet).

    >>> g = carried_vector(np.r_[1.0, np.zeros(5), -1.0, np.zeros(5)], [0, 0, 1], 1)
    >>> sorted(g), complex(g[1][1]), complex(g[0][6])
    ([-1, 0, 1], -0.5j, (-1+0j))
    """
    w = np.asarray(w, dtype=float).reshape(12)
    QT = transpose(carrier_projection(axis, spin))
    return {k: v @ w for k, v in QT.items() if np.any(v @ w)}


def planet_mesh_term(
    member_dofs: ArrayLike,
    planet_dofs: ArrayLike,
    w: np.ndarray,
    axis: object,
    spin: int,
    mesh_harmonic: int,
    stiffness: Mapping[int, complex],
    damping: float = 0.0,
    transmission_error: Mapping[int, complex] | None = None,
) -> SpeedTerm:
    """A sun-planet or ring-planet mesh: ``k(t) w w^T``, ``c w w^T`` and the static
    transmission error load ``k(t) e(t) w`` in the carrier's axes.

    ``stiffness`` and ``transmission_error`` are two-sided ``{j: x_j}`` over mesh harmonics
    (already phased for this planet, :func:`~rheolin.mechanics.planetary.phased`);
    ``mesh_harmonic`` is the mesh frequency in units of ``w1``.

    >>> w = np.zeros(12); w[5], w[11] = 0.05, 0.03
    >>> t = planet_mesh_term(range(6), range(6, 12), w, [0, 0, 1], 1, 20, {0: 1e8, 1: 1e7})
    >>> sorted(t.K[0]), float(t.K[0][0][5, 11].real)
    ([-20, 0, 20], 150000.0)
    """
    if damping < 0:
        raise ModelError(f"`damping` must be >= 0 [N s/m], got {damping!r}")
    w = np.asarray(w, dtype=float).reshape(12)
    ww = np.outer(w, w)
    m = int(mesh_harmonic)
    k = _two_sided(stiffness)
    K = {j * m: kj * ww for j, kj in k.items() if kj != 0}
    f = None
    if transmission_error:
        te = mesh_convolve(k, _two_sided(transmission_error))
        f = {j * m: v * w for j, v in te.items() if v != 0}
    return carried_speed_term(member_dofs, planet_dofs, axis, spin, K, damping * ww, f)


def _two_sided(coefficients: Mapping[int, complex]) -> dict[int, complex]:
    """A real signal's coefficients with the missing ``x_{-j} = conj(x_j)`` filled in."""
    out = {int(j): complex(v) for j, v in coefficients.items()}
    for j, v in list(out.items()):
        out.setdefault(-j, v.conjugate())
    return out


def planet_bearing_term(
    carrier_dofs: ArrayLike,
    planet_dofs: ArrayLike,
    pin: ArrayLike,
    axis: object,
    spin: int,
    stiffness: np.ndarray,
    damping: np.ndarray | None = None,
    pin_error: ArrayLike | None = None,
) -> SpeedTerm:
    """The planet bearing on its pin, in the carrier's axes.

    Parameters
    ----------
    carrier_dofs, planet_dofs
        The carrier node's DOFs (inertial) and the planet's (carrier axes).
    pin
        The pin (planet centre) from the carrier node [m], carrier axes at ``t = 0``.
    stiffness, damping
        6x6 on the planet's motion relative to the pin, carrier axes.
    pin_error
        The pin's position error (3 translations, or 6 with rotations) [m]: the bearing's
        unloaded position is the pin moved by it.

    Examples
    --------
    An isotropic 1e8 N/m bearing, a 50 um tangential pin error at radius 0.1 m: the planet
    is pulled 5 kN towards it, the carrier feels the reaction and its moment (5 kN x 0.1 m).

    >>> K = np.diag([1e8, 1e8, 0, 0, 0, 0])
    >>> t = planet_bearing_term(range(6), range(6, 12), [0.1, 0, 0], [0, 0, 1], 0, K,
    ...                         pin_error=[0, 50e-6, 0])
    >>> np.round(t.f[0][0].real[[1, 5, 7]], 6) + 0.0
    array([-5000., -500.,  5000.])
    """
    L = lever(pin)
    L = np.eye(6) if L is None else L
    G = np.hstack([-L, np.eye(6)])
    KB = np.asarray(stiffness, dtype=float)
    if KB.shape != (6, 6):
        raise ModelError(f"planet bearing `stiffness` must be 6x6, got {KB.shape}")
    C = None if damping is None else G.T @ np.asarray(damping, dtype=float) @ G
    f = None
    if pin_error is not None:
        eps = np.zeros(6)
        e = np.asarray(pin_error, dtype=float).ravel()
        if e.size not in (3, 6) or not np.all(np.isfinite(e)):
            raise ModelError(f"`pin_errors` entries must be 3 or 6 finite values, got {e!r}")
        eps[: e.size] = e
        if np.any(eps):
            f = {0: G.T @ KB @ eps}
    return carried_speed_term(carrier_dofs, planet_dofs, axis, spin, {0: G.T @ KB @ G}, C, f)


def planet_inertia_term(
    planet_dofs: ArrayLike,
    mass: float,
    inertia: np.ndarray,
    axis: object,
    spin: int,
    carrier_spin: int,
    orbit: ArrayLike = (0.0, 0.0, 0.0),
) -> SpeedTerm:
    """A planet's inertia in the carrier's axes (spinning at ``spin * w1`` absolutely), and the
    centripetal load of its orbit ``orbit`` (the planet centre from the carrier's axis, m).

    >>> t = planet_inertia_term(range(6), 2.0, [0.01, 0.01, 0.02], [0, 0, 1], -3, 1, [0.1, 0, 0])
    >>> t.D[1][0][:2, :2] + 0.0, t.f[2][0][:3] + 0.0
    (array([[ 0., -4.], [ 4.,  0.]]), array([0.2, 0. , 0. ]))
    """
    e = unit_axis(axis)
    J = np.asarray(inertia, dtype=float)
    node = RigidNode(mass, np.diag(J) if J.shape == (3,) else J)
    dofs = np.asarray(planet_dofs, dtype=np.int64).reshape(6)
    own = node.speed_term(0, e, spin)
    own.dofs = dofs
    blocks = {int(dofs[0]) // 3, int(dofs[3]) // 3}
    out = in_frame(own, blocks, e, carrier_spin)
    out.f = {p: v for p, v in out.f.items() if any(np.any(x) for x in v.values())}
    orbit_load = centripetal_load(dofs, mass, e, carrier_spin, orbit)
    if orbit_load.f:
        out.f[2] = add_series(out.f.get(2, {}), orbit_load.f[2])
    return out


def centripetal_load(
    planet_dofs: ArrayLike, mass: float, axis: object, carrier_spin: int, orbit: ArrayLike
) -> SpeedTerm:
    """The force ``m W_c^2 r`` that keeps a planet on its orbit ``orbit`` (its centre from the
    carrier's axis [m]), a static load on its bearing in the carrier's axes (quadratic in the
    speed).

    >>> centripetal_load(range(6), 2.0, [0, 0, 1], 3, [0.1, 0.0, 0.5]).f[2][0][:3]
    array([1.8, 0. , 0. ])
    """
    e = unit_axis(axis)
    r = np.asarray(orbit, dtype=float).reshape(3)
    r = r - (r @ e) * e
    f = np.zeros(6)
    f[:3] = float(mass) * carrier_spin**2 * r
    out = SpeedTerm(np.asarray(planet_dofs, dtype=np.int64).reshape(6))
    if np.any(f):
        out.f[2] = {0: f}
    return out
