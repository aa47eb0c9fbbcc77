"""Rigid node (disk, gear blank, coupling) spinning with its body (docs/rotating-bodies.md).

A rigid node has mass ``m``, centre-of-mass offset ``c_B`` from the node (static unbalance
``m c_B``) and inertia tensor ``J_B`` about the centre of mass, both in body axes (which coincide
with the global axes at ``t = 0``). Inertia products in ``J_B`` are allowed (dynamic unbalance).
With ``c = R c_B`` and ``J = R J_B R^T`` the exact linearization of Newton–Euler about the uniform
rotation ``R(t)`` (orientation ``(I + [phi]x) R``) gives, rows (force, moment about the node),
columns ``(u, phi)``::

    M = [ m I      , -m[c]x                            ]
        [ m[c]x    ,  J - m[c]x[c]x                    ]
    D = [ 0        , -2m[c']x                          ]
        [ 0        ,  J' - W[J e]x - 2m[c]x[c']x       ]
    K = [ 0        , -m[c'']x                          ]
        [ 0        , -W[J' e]x - m[c]x[c'']x + m[c'']x[c]x ]
    f = ( -m c''  ,  -W J' e - m c x c'' )

All products are evaluated exactly as finite Fourier series (harmonics ``0, +-s, +-2s``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ModelError
from ._term import SpeedTerm, Term
from .rotation import clean_series, derivative, rotation_series, series_product, skew, unit_axis
from .sections import material_constants

__all__ = [
    "RigidNode",
    "couple_unbalance",
    "disk",
    "disk_node",
    "rigid_node_coefficients",
    "static_unbalance",
]

Series = dict[int, np.ndarray]


@dataclass(frozen=True)
class RigidNode:
    """Mass properties of a rigid node in body axes.

    Parameters
    ----------
    mass
        Mass ``m`` [kg], >= 0.
    inertia
        Inertia tensor ``J_B`` about the centre of mass [kg m^2], symmetric 3x3 (or 3 principal
        values).
    com
        Centre-of-mass offset ``c_B`` from the node [m].

    Examples
    --------
    >>> node = RigidNode(2.0, [0.1, 0.1, 0.2], com=[1e-4, 0, 0])
    >>> float(node.inertia[2, 2]), node.static_unbalance
    (0.2, array([0.0002, 0.    , 0.    ]))
    """

    mass: float
    inertia: np.ndarray
    com: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        m = float(self.mass)
        if not np.isfinite(m) or m < 0.0:
            raise ModelError(f"`mass` must be finite and >= 0, got {self.mass!r}")
        J = np.asarray(self.inertia, dtype=float)
        if J.shape == (3,):
            J = np.diag(J)
        if J.shape != (3, 3) or not np.all(np.isfinite(J)):
            raise ModelError(f"`inertia` must be a 3x3 matrix or 3 values, got shape {J.shape}")
        if not np.allclose(J, J.T, rtol=1e-12, atol=1e-14 * np.max(np.abs(J), initial=0.0)):
            raise ModelError("`inertia` must be symmetric")
        J = 0.5 * (J + J.T)
        if np.min(np.linalg.eigvalsh(J), initial=0.0) < -1e-12 * np.max(np.abs(J), initial=0.0):
            raise ModelError("`inertia` must be positive semidefinite")
        c = np.asarray(self.com, dtype=float).reshape(-1)
        if c.shape != (3,) or not np.all(np.isfinite(c)):
            raise ModelError(f"`com` must be a finite 3-vector, got {self.com!r}")
        object.__setattr__(self, "mass", m)
        object.__setattr__(self, "inertia", J)
        object.__setattr__(self, "com", c)

    @property
    def static_unbalance(self) -> np.ndarray:
        """Static unbalance ``m c_B`` [kg m]."""
        return self.mass * self.com

    def coefficients(
        self, axis: object, s: int, w1: float
    ) -> tuple[Series, Series, Series, Series]:
        """``(M, D, K, f)`` Fourier coefficients (6x6, 6x6, 6x6, 6); see the module docstring."""
        return rigid_node_coefficients(self.mass, self.inertia, self.com, axis, s, w1)

    def term(self, node: int, axis: object, s: int, w1: float) -> Term:
        """:class:`Term` on the 6 DOFs of global node ``node``.

        >>> t = RigidNode(1.0, [1.0, 1.0, 2.0]).term(3, [0, 0, 1], 1, 10.0)
        >>> t.dofs.tolist(), t.D[0][3:5, 3:5] + 0.0
        ([18, 19, 20, 21, 22, 23], array([[ 0., 20.], [-20., 0.]]))
        """
        return self.speed_term(node, axis, s).at(w1)

    def speed_term(self, node: int, axis: object, s: int) -> SpeedTerm:
        """:meth:`term` as a polynomial in ``w1``: ``M`` is constant, ``D`` linear, ``K``
        and ``f`` quadratic (each homogeneous, so the coefficients at ``w1 = 1`` are exact).

        >>> t = RigidNode(1.0, [1.0, 1.0, 2.0]).speed_term(0, [0, 0, 1], 1)
        >>> sorted(t.M), sorted(t.D), sorted(t.K), sorted(t.f)
        ([0], [1], [2], [2])
        """
        if isinstance(node, bool) or not isinstance(node, (int, np.integer)) or node < 0:
            raise ModelError(f"`node` must be a nonnegative integer, got {node!r}")
        M, D, K, f = self.coefficients(axis, s, 1.0)
        dofs = 6 * int(node) + np.arange(6)
        return SpeedTerm(dofs=dofs, M={0: M}, D={1: D}, K={2: K}, f={2: f})


def _add(*series: Series) -> Series:
    out: Series = {}
    for ser in series:
        for k, v in ser.items():
            out[k] = out[k] + v if k in out else np.asarray(v, dtype=complex)
    return out


def _scale(a: float, ser: Series) -> Series:
    return {k: a * v for k, v in ser.items()}


def _skew(ser: Series) -> Series:
    return {k: skew(v) for k, v in ser.items()}


def _matvec(ser: Series, v: np.ndarray) -> Series:
    return {k: x @ v for k, x in ser.items()}


def _block6(tt: Series, tr: Series, rt: Series, rr: Series) -> Series:
    keys = set(tt) | set(tr) | set(rt) | set(rr) | {0}
    z = np.zeros((3, 3), dtype=complex)
    out = {}
    for k in keys:
        out[k] = np.block([[tt.get(k, z), tr.get(k, z)], [rt.get(k, z), rr.get(k, z)]])
    return clean_series(out)


def rigid_node_coefficients(
    mass: float, inertia: np.ndarray, com: np.ndarray, axis: object, s: int, w1: float
) -> tuple[Series, Series, Series, Series]:
    """Exact Fourier coefficients ``(M, D, K, f)`` of a spinning rigid node.

    Parameters
    ----------
    mass, inertia, com
        ``m``, ``J_B`` (3x3, about the centre of mass), ``c_B`` in body axes.
    axis, s, w1
        Spin axis ``e``, spin harmonic ``s`` and base frequency ``w1``: ``W = s * w1``.

    Returns
    -------
    M, D, K : dict[int, ndarray (6, 6)]
    f : dict[int, ndarray (6,)]

    Examples
    --------
    Axisymmetric disk, centred: only the gyroscopic coupling ``D = -W J_p [e]x``.

    >>> M, D, K, f = rigid_node_coefficients(1.0, np.diag([1.0, 1.0, 3.0]), np.zeros(3),
    ...                                      [0, 0, 1], 2, 5.0)
    >>> sorted(M), sorted(D), D[0][3:5, 3:5] + 0.0
    ([0], [0], array([[ 0., 30.], [-30., 0.]]))
    >>> float(np.abs(K[0]).max()), float(np.abs(f[0]).max())
    (0.0, 0.0)
    """
    e = unit_axis(axis)
    w1 = float(w1)
    if not np.isfinite(w1):
        raise ModelError(f"`w1` must be finite, got {w1!r}")
    m = float(mass)
    J_B = np.asarray(inertia, dtype=float)
    c_B = np.asarray(com, dtype=float).reshape(3)
    R = rotation_series(e, s)
    W = s * w1
    c0 = {k: P @ c_B for k, P in R.items()}
    c1 = derivative(c0, w1)
    c2 = derivative(c0, w1, 2)
    J0 = series_product(series_product(R, {0: J_B}), {k: P.T for k, P in R.items()})
    J1 = derivative(J0, w1)
    I3 = {0: np.eye(3)}
    sc, sc1, sc2 = _skew(c0), _skew(c1), _skew(c2)
    M = _block6(
        _scale(m, I3), _scale(-m, sc), _scale(m, sc), _add(J0, _scale(-m, series_product(sc, sc)))
    )
    D = _block6(
        {},
        _scale(-2 * m, sc1),
        {},
        _add(J1, _scale(-W, _skew(_matvec(J0, e))), _scale(-2 * m, series_product(sc, sc1))),
    )
    K = _block6(
        {},
        _scale(-m, sc2),
        {},
        _add(
            _scale(-W, _skew(_matvec(J1, e))),
            _scale(-m, series_product(sc, sc2)),
            _scale(m, series_product(sc2, sc)),
        ),
    )
    ft = _scale(-m, c2)
    fr = _add(_scale(-W, _matvec(J1, e)), _scale(-m, series_product(c0, c2, np.cross)))
    keys = set(ft) | set(fr) | {0}
    z = np.zeros(3, dtype=complex)
    f = clean_series({k: np.concatenate([ft.get(k, z), fr.get(k, z)]) for k in keys})
    return M, D, K, f


def disk(
    outer_diameter: float,
    width: float,
    density: float,
    inner_diameter: float = 0.0,
    axis: object = (0.0, 0.0, 1.0),
    com: object = (0.0, 0.0, 0.0),
) -> RigidNode:
    """Rigid node of a uniform disk / gear blank (annulus) with its symmetry axis along ``axis``.

    ``m = rho pi (D^2 - d^2) w / 4``, polar ``J_p = m (D^2 + d^2) / 8``, diametral
    ``J_d = J_p / 2 + m w^2 / 12``.

    >>> node = disk(0.2, 0.02, 7850.0, axis=[0, 0, 1])
    >>> round(node.mass, 4), round(float(node.inertia[2, 2]), 6)
    (4.9323, 0.024662)
    """
    Do, di, w, rho = (float(x) for x in (outer_diameter, inner_diameter, width, density))
    for name, val in (("outer_diameter", Do), ("width", w), ("density", rho)):
        if not np.isfinite(val) or val <= 0.0:
            raise ModelError(f"`{name}` must be finite and > 0, got {val!r}")
    if not 0.0 <= di < Do:
        raise ModelError(f"`inner_diameter` must be in [0, outer_diameter), got {di!r}")
    e = unit_axis(axis)
    m = rho * np.pi * (Do**2 - di**2) * w / 4.0
    Jp = m * (Do**2 + di**2) / 8.0
    Jd = Jp / 2.0 + m * w**2 / 12.0
    J = Jd * np.eye(3) + (Jp - Jd) * np.outer(e, e)
    return RigidNode(m, J, np.asarray(com, dtype=float))


#: The global direction whose projection onto a disk's plane is its angle 0 (unbalance).
UNBALANCE_REFERENCE = (1.0, 0.0, 0.0)
#: ... and the one used instead for bodies turning about (nearly) that direction.
UNBALANCE_REFERENCE_ALONG = (0.0, 1.0, 0.0)


def unbalance_reference(axis: object, reference: object = None) -> np.ndarray:
    """The radial unit vector at angle 0 about ``axis``: the projection of the global
    ``reference`` direction (default :data:`UNBALANCE_REFERENCE`, x) onto the plane normal to
    the axis; with the default, a body turning about x takes y. Angles run from it towards
    ``axis x reference`` (right-handed about the spin axis).

    >>> unbalance_reference([0, 0, 1]).tolist(), unbalance_reference([1, 0, 0]).tolist()
    ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    """
    e = unit_axis(axis)
    given = reference is not None
    ref = np.asarray(UNBALANCE_REFERENCE if reference is None else reference, dtype=float)
    if ref.shape != (3,) or not np.all(np.isfinite(ref)) or np.linalg.norm(ref) == 0:
        raise ModelError(f"`unbalance_reference` must be a nonzero 3-vector, got {reference!r}")
    ref = ref / np.linalg.norm(ref)
    if abs(float(ref @ e)) > np.cos(np.radians(1.0)):
        if given:
            raise ModelError(
                f"`unbalance_reference` {np.round(ref, 6).tolist()} is along the spin axis "
                f"{np.round(e, 6).tolist()} of a body with unbalance: choose a direction across it"
            )
        ref = np.asarray(UNBALANCE_REFERENCE_ALONG, dtype=float)
    x = ref - (ref @ e) * e
    return np.asarray(x / np.linalg.norm(x))


def _perp_direction(
    axis: object, angle: float, reference: object = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit vectors ``(e, a, b)``: ``a`` at ``angle`` from the reference radial direction."""
    e = unit_axis(axis)
    x = unbalance_reference(e, reference)
    y = np.cross(e, x)
    a = np.cos(angle) * x + np.sin(angle) * y
    return e, a, np.cross(e, a)


def static_unbalance(
    node: RigidNode,
    mass_radius: float,
    angle: float = 0.0,
    axis: object = (0.0, 0.0, 1.0),
    reference: object = None,
) -> RigidNode:
    """Add a static unbalance ``U = m_u r_u`` [kg m] at ``angle`` [rad] about ``axis``.

    Angle 0 is :func:`unbalance_reference` (the global x direction projected onto the plane
    normal to the axis; y for a body turning about x). The centre of mass moves by
    ``U / m`` (the unbalance mass itself is neglected next to ``m``).

    >>> n = static_unbalance(RigidNode(2.0, [1, 1, 1]), 1e-3, np.pi / 2)
    >>> np.round(n.com, 6)
    array([0.    , 0.0005, 0.    ])
    """
    if node.mass <= 0.0:
        raise ModelError("`node` must have a positive mass to carry a static unbalance")
    _, a, _ = _perp_direction(axis, angle, reference)
    return RigidNode(node.mass, node.inertia, node.com + float(mass_radius) / node.mass * a)


def couple_unbalance(
    node: RigidNode,
    couple: float,
    angle: float = 0.0,
    axis: object = (0.0, 0.0, 1.0),
    reference: object = None,
) -> RigidNode:
    """Add a couple (dynamic) unbalance ``U_c = m_u r_u l`` [kg m^2] as an inertia product.

    Two masses ``m_u`` at radius ``r_u``, axial distance ``l`` apart and opposite in angle, add
    the product of inertia ``-U_c`` between the spin axis and the radial direction at
    ``angle``; the principal axis tilts by ``U_c / (J_p - J_d)``.

    >>> n = couple_unbalance(RigidNode(1.0, [1.0, 1.0, 2.0]), 1e-3)
    >>> float(n.inertia[0, 2])
    -0.001
    """
    e, a, _ = _perp_direction(axis, angle, reference)
    dJ = -float(couple) * (np.outer(a, e) + np.outer(e, a))
    return RigidNode(node.mass, node.inertia + dJ, node.com)


def disk_node(
    existing: RigidNode | None,
    axis: np.ndarray,
    reference: object,
    body: str,
    node: int,
    mass: float | None,
    inertia: object | None,
    outer_diameter: float | None,
    width: float | None,
    density: float | None,
    inner_diameter: float,
    unbalance: float,
    unbalance_angle: float,
    couple_unbalance_: float,
    couple_angle: float,
    material: str | None,
    axial_offset: float,
) -> RigidNode:
    """The rigid node of a disk at ``node`` of ``body`` (``Model.add_disk`` names the
    arguments): its mass and inertia, or its geometry and density (or named ``material``),
    or the ``existing`` disk there; then its unbalances and axial offset.

    >>> n = disk_node(None, np.array([0.0, 0.0, 1.0]), None, "s", 0, 2.0, [1, 1, 1], None,
    ...               None, None, 0.0, 1e-3, 0.0, 0.0, 0.0, None, 0.1)
    >>> n.com.tolist()
    [0.0005, 0.0, 0.1]
    """
    if mass is not None or inertia is not None:
        if mass is None or inertia is None:
            raise ModelError("`mass` and `inertia` must be given together")
        rn = RigidNode(mass, np.asarray(inertia, dtype=float))
    elif outer_diameter is not None:
        if width is None:
            raise ModelError("`width` is required with `outer_diameter`")
        rho = material_constants(material, {"density": density}, f"add_disk({body!r})")
        rn = disk(outer_diameter, width, float(rho["density"]), inner_diameter, axis=axis)
    elif existing is not None:
        rn = existing
    else:
        raise ModelError("give `mass` and `inertia`, or `outer_diameter` and `width`")
    if unbalance:
        rn = static_unbalance(rn, unbalance, unbalance_angle, axis=axis, reference=reference)
    if couple_unbalance_:
        rn = couple_unbalance(rn, couple_unbalance_, couple_angle, axis=axis, reference=reference)
    if existing is not None and (mass is not None or outer_diameter is not None):
        raise ModelError(f"`node`: node {node} of body {body!r} already has a disk")
    if axial_offset:
        if not np.isfinite(axial_offset):
            raise ModelError(f"`axial_offset` must be finite, got {axial_offset!r}")
        if rn.mass <= 0.0:
            raise ModelError("`axial_offset` needs a disk with mass")
        rn = RigidNode(rn.mass, rn.inertia, rn.com + float(axial_offset) * np.asarray(axis))
    return rn
