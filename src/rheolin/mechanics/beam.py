"""Timoshenko beam element along the spin axis (2 nodes x 6 DOF).

Local axes: ``x`` from node 1 to node 2, ``y``/``z`` the section's principal axes. Local DOFs per
node ``(u, v, w, theta_x, theta_y, theta_z)``. Axial, torsion and two bending planes with shear
deformation (Timoshenko factors ``Phi = 12 E I / (kappa G A L^2)``); consistent translational
mass with shear (Friedman & Kosmatka 1993).

Rotary inertia, the choice made here (docs/rotating-bodies.md):

* ``rotary="consistent"`` (default for axisymmetric sections): consistent rotary inertia of both
  bending planes and of torsion in ``M_B``, and the consistent gyroscopic matrix
  ``G_B = -rho I_p \\int N_phi^T [e]x N_phi dx`` (``D += W G_B``), the exact rotating-frame
  counterpart of the rigid-node row ``D = -W J_p [e]x`` for an axisymmetric section.
* ``rotary="lumped"`` (default otherwise, forced for ``Iy != Iz``): the rotary inertia of half the
  element, ``rho L / 2 * diag(I_p, I_y, I_z)``, sits at each node and enters through the rigid-node
  rows (:func:`~rheolin.mechanics.rigid.rigid_node_coefficients` with ``m = 0``), which give the
  gyroscopic coupling and the ``2W`` parametric rotary inertia of a non-circular section. The
  translational mass then uses the mean shear parameter of the two planes so that it is rotation
  invariant, as the physical translational inertia is.

Stiffness and material damping ``D_B = beta K_B`` rotate with the body:
``K += Rt K_B Rt^T + Rt D_B Rt'^T``, ``D += Rt D_B Rt^T``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..errors import ModelError
from ._term import SpeedTerm, Term
from .rigid import rigid_node_coefficients
from .rotation import add_series, circulatory_matrix, clean_series, rotate_body_matrix, unit_axis
from .sections import Material, Section

__all__ = [
    "BeamMatrices",
    "beam_body_matrices",
    "beam_local_matrices",
    "beam_speed_term",
    "beam_term",
    "local_axes",
]

Rotary = Literal["auto", "consistent", "lumped"]
_S = np.diag([1.0, -1.0, 1.0, -1.0])  # x-y plane pattern -> x-z plane (theta_y = -dw/dx)
_XY = [1, 5, 7, 11]  # (v1, theta_z1, v2, theta_z2)
_XZ = [2, 4, 8, 10]  # (w1, theta_y1, w2, theta_y2)


def _bending_stiffness(EI: float, L: float, phi: float) -> np.ndarray:
    return (
        EI
        / ((1.0 + phi) * L**3)
        * np.array(
            [
                [12.0, 6 * L, -12.0, 6 * L],
                [6 * L, (4 + phi) * L**2, -6 * L, (2 - phi) * L**2],
                [-12.0, -6 * L, 12.0, -6 * L],
                [6 * L, (2 - phi) * L**2, -6 * L, (4 + phi) * L**2],
            ]
        )
    )


def _translational_mass(rhoA: float, L: float, p: float) -> np.ndarray:
    a = 13 / 35 + 7 * p / 10 + p**2 / 3
    b = (11 / 210 + 11 * p / 120 + p**2 / 24) * L
    c = 9 / 70 + 3 * p / 10 + p**2 / 6
    d = (13 / 420 + 3 * p / 40 + p**2 / 24) * L
    e = (1 / 105 + p / 60 + p**2 / 120) * L**2
    g = (1 / 140 + p / 60 + p**2 / 120) * L**2
    m = np.array([[a, b, c, -d], [b, e, d, -g], [c, d, a, -b], [-d, -g, -b, e]])
    return rhoA * L / (1 + p) ** 2 * m


def _rotary_shape(L: float, p: float) -> np.ndarray:
    """``\\int N_r^T N_r dx`` for the section rotation of the x-y plane (times rho I = mass)."""
    a = 6 / 5
    b = (1 / 10 - p / 2) * L
    c = (2 / 15 + p / 6 + p**2 / 3) * L**2
    d = (1 / 30 + p / 6 - p**2 / 6) * L**2
    m = np.array([[a, b, -a, b], [b, c, -b, -d], [-a, -b, a, -b], [b, -d, -b, c]])
    return m / ((1 + p) ** 2 * L)


def _shear_parameter(E: float, I: float, kappa: float, G: float, A: float, L: float) -> float:
    return 0.0 if np.isinf(kappa) else 12.0 * E * I / (kappa * G * A * L**2)


def beam_local_matrices(
    length: float, section: Section, material: Material, rotary: Rotary = "auto"
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """Local ``(M, K, G, J_node)`` of the element (12x12; ``J_node`` 3x3 or ``None``).

    ``G`` is the gyroscopic matrix per unit spin speed about local ``+x`` (``D = W G``); with
    lumped rotary inertia ``G`` is zero and ``J_node = rho L / 2 diag(I_p, I_y, I_z)`` is the
    rotary inertia to attach to each node through the rigid-node rows.

    Examples
    --------
    >>> from rheolin.mechanics.sections import Material, solid_circular
    >>> M, K, G, J = beam_local_matrices(1.0, solid_circular(0.01), Material(1.0, 1.0, nu=0.3))
    >>> float(M[0, 0] + M[0, 6]) == float(np.pi * 0.01**2 / 4 / 2), J is None
    (True, True)
    """
    L = float(length)
    if not np.isfinite(L) or L <= 0.0:
        raise ModelError(f"`length` must be finite and > 0, got {length!r}")
    if rotary not in ("auto", "consistent", "lumped"):
        raise ModelError(f"`rotary` must be 'auto', 'consistent' or 'lumped', got {rotary!r}")
    sec, mat = section, material
    if rotary == "consistent" and not sec.axisymmetric:
        raise ModelError("`rotary='consistent'` needs an axisymmetric section; use 'lumped'")
    lumped = rotary == "lumped" or (rotary == "auto" and not sec.axisymmetric)
    E, G, rho, A = mat.E, float(mat.G), mat.density, sec.area  # type: ignore[arg-type]
    py = _shear_parameter(E, sec.Iz, sec.kappa_y, G, A, L)  # x-y plane: bending by Iz
    pz = _shear_parameter(E, sec.Iy, sec.kappa_z, G, A, L)  # x-z plane: bending by Iy
    K = np.zeros((12, 12))
    M = np.zeros((12, 12))
    Gy = np.zeros((12, 12))
    bar = np.array([[1.0, -1.0], [-1.0, 1.0]])
    K[np.ix_([0, 6], [0, 6])] = E * A / L * bar
    K[np.ix_([3, 9], [3, 9])] = G * sec.torsion_constant / L * bar
    K[np.ix_(_XY, _XY)] = _bending_stiffness(E * sec.Iz, L, py)
    K[np.ix_(_XZ, _XZ)] = _S @ _bending_stiffness(E * sec.Iy, L, pz) @ _S
    cons = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0
    M[np.ix_([0, 6], [0, 6])] = rho * A * L * cons
    if lumped:
        pm = 0.5 * (py + pz)
        M[np.ix_(_XY, _XY)] = _translational_mass(rho * A, L, pm)
        M[np.ix_(_XZ, _XZ)] = _S @ _translational_mass(rho * A, L, pm) @ _S
        return M, K, Gy, rho * L / 2.0 * np.diag([sec.polar, sec.Iy, sec.Iz])
    M[np.ix_([3, 9], [3, 9])] = rho * sec.polar * L * cons
    R = _rotary_shape(L, py)
    M[np.ix_(_XY, _XY)] = _translational_mass(rho * A, L, py) + rho * sec.Iz * R
    M[np.ix_(_XZ, _XZ)] = _S @ (_translational_mass(rho * A, L, pz) + rho * sec.Iy * R) @ _S
    # theta_z = N_r d_xy, theta_y = -N_r S d_xz; G = -rho Ip \int N^T [e_x]x N, [e_x]x th =
    # (0, -th_z, th_y): G[xz, xy] = rho Ip \int N_y^T N_z = -rho Ip S R, G[xy, xz] = -G[xz, xy]^T
    Gy[np.ix_(_XZ, _XY)] = -rho * sec.polar * _S @ R
    Gy[np.ix_(_XY, _XZ)] = rho * sec.polar * R @ _S
    return M, K, Gy, None


def local_axes(direction: object, y_axis: object | None = None) -> np.ndarray:
    """Rows: the beam's local ``x, y, z`` axes in global coordinates.

    ``y_axis`` (the section's local y at ``t = 0``) is projected onto the plane normal to
    ``direction``; by default the global axis least aligned with ``direction`` is used.

    >>> local_axes([0, 0, 1])
    array([[0., 0., 1.],
           [1., 0., 0.],
           [0., 1., 0.]])
    """
    x = unit_axis(direction, "direction")
    ref = np.eye(3)[int(np.argmin(np.abs(x)))] if y_axis is None else unit_axis(y_axis, "y_axis")
    y = ref - (ref @ x) * x
    if np.linalg.norm(y) < 1e-9:
        raise ModelError("`y_axis` must not be parallel to the beam `direction`")
    y /= np.linalg.norm(y)
    return np.array([x, y, np.cross(x, y)]) + 0.0


@dataclass(frozen=True)
class BeamMatrices:
    """Body-frame element matrices in global axes at ``t = 0`` (12x12).

    ``gyroscopic`` is ``G_B`` per unit spin speed about ``+direction`` (``D += W G_B``),
    ``node_inertia`` the lumped rotary inertia per node (3x3) or ``None``.
    """

    M: np.ndarray
    K: np.ndarray
    D: np.ndarray
    gyroscopic: np.ndarray
    node_inertia: np.ndarray | None


def beam_body_matrices(
    length: float,
    section: Section,
    material: Material,
    direction: object,
    y_axis: object | None = None,
    rotary: Rotary = "auto",
) -> BeamMatrices:
    """Element matrices transformed to global axes (the body frame at ``t = 0``).

    >>> from rheolin.mechanics.sections import Material, solid_circular
    >>> b = beam_body_matrices(0.5, solid_circular(0.02), Material(2e11, 7800.0, nu=0.3),
    ...                        [1, 0, 0])
    >>> bool(np.allclose(b.K, b.K.T)), b.M.shape
    (True, (12, 12))
    """
    M, K, G, J = beam_local_matrices(length, section, material, rotary)
    T = local_axes(direction, y_axis)
    Tb = np.kron(np.eye(4), T)
    J_g = None if J is None else T.T @ J @ T
    return BeamMatrices(
        Tb.T @ M @ Tb, Tb.T @ K @ Tb, material.damping_beta * (Tb.T @ K @ Tb), Tb.T @ G @ Tb, J_g
    )


def beam_term(
    nodes: tuple[int, int],
    length: float,
    section: Section,
    material: Material,
    direction: object,
    axis: object,
    s: int,
    w1: float,
    y_axis: object | None = None,
    rotary: Rotary = "auto",
) -> Term:
    """:class:`Term` of a beam element between global nodes ``nodes`` spinning with its body.

    Parameters
    ----------
    nodes
        Global node indices ``(i, j)``; DOFs ``6 i .. 6 i + 5, 6 j .. 6 j + 5``.
    length, section, material
        Element length [m], cross-section, material (``damping_beta`` = rotating damping).
    direction
        Unit vector from node ``i`` to node ``j``; must be parallel to ``axis`` if ``s != 0``.
    axis, s, w1
        Spin axis, spin harmonic and base frequency: ``W = s * w1``.
    y_axis
        Section local y at ``t = 0`` (orientation of a non-axisymmetric section).
    rotary
        Rotary inertia model, see the module docstring.

    Examples
    --------
    >>> from rheolin.mechanics.sections import Material, general_section
    >>> sec = general_section(1e-4, 2e-9, 1e-9, 2e-9)
    >>> t = beam_term((0, 1), 0.1, sec, Material(2e11, 7800.0, nu=0.3), [0, 0, 1], [0, 0, 1],
    ...               1, 100.0)
    >>> sorted(t.K), t.dofs.tolist() == list(range(12))
    ([-2, 0, 2], True)
    """
    i, j = nodes
    for n in (i, j):
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
            raise ModelError(f"`nodes` must be two nonnegative integers, got {nodes!r}")
    if i == j:
        raise ModelError(f"`nodes` must be two different nodes, got {nodes!r}")
    d = unit_axis(direction, "direction")
    e = unit_axis(axis)
    if s != 0 and np.linalg.norm(np.cross(d, e)) > 1e-9:
        raise ModelError("a spinning beam's `direction` must be parallel to its spin `axis`")
    b = beam_body_matrices(length, section, material, d, y_axis, rotary)
    sign = float(np.sign(d @ e)) if s != 0 else 1.0
    at = beam_speed_term((int(i), int(j)), b, e, s, sign).at(w1)
    return Term(
        dofs=at.dofs,
        M=clean_series(at.M),
        D=clean_series(at.D),
        K=clean_series(at.K),
        f=clean_series(at.f) if at.f else {},
    )


def _pad(series: dict[int, np.ndarray], off: int) -> dict[int, np.ndarray]:
    """Rigid-node rows of one node (6x6 or 6) placed on node ``off // 6`` of the element."""
    return {
        k: np.pad(v, ((off, 6 - off), (off, 6 - off)) if v.ndim == 2 else (off, 6 - off))
        for k, v in series.items()
    }


def beam_speed_term(
    nodes: tuple[int, int], b: BeamMatrices, axis: np.ndarray, s: int, sign: float = 1.0
) -> SpeedTerm:
    """A beam element of :func:`beam_body_matrices` ``b`` between global ``nodes``, spinning
    at ``s w1`` about the unit ``axis``, as a polynomial in ``w1`` (a :class:`SpeedTerm`).

    Power 0: ``M``, ``Rt K_B Rt^T``, ``Rt D_B Rt^T``; power 1: the circulatory stiffness and
    the gyroscopic terms; power 2: the lumped rotary inertia's centripetal rows. ``sign`` is
    ``+1`` when the element points along ``axis``, ``-1`` against it. :func:`beam_term`
    checks its arguments and evaluates this at ``w1``.

    >>> from rheolin.mechanics.sections import Material, solid_circular
    >>> Z = np.array([0.0, 0.0, 1.0])
    >>> b = beam_body_matrices(0.1, solid_circular(0.02), Material(2e11, 7800.0, nu=0.3), Z)
    >>> t = beam_speed_term((0, 1), b, Z, 1)
    >>> sorted(t.M), sorted(t.D), sorted(t.K)
    ([0], [0, 1], [0, 1])
    """
    e = axis
    M = {0: rotate_body_matrix(b.M, e, s)}
    K = {0: rotate_body_matrix(b.K, e, s), 1: circulatory_matrix(b.D, e, s, 1.0)}
    D = {0: rotate_body_matrix(b.D, e, s), 1: {0: sign * s * b.gyroscopic}}
    f: dict[int, dict[int, np.ndarray]] = {}
    if b.node_inertia is not None:
        Mr, Dr, Kr, fr = rigid_node_coefficients(0.0, b.node_inertia, np.zeros(3), e, s, 1.0)
        for off in (0, 6):
            M[0] = add_series(M[0], _pad(Mr, off))
            D[1] = add_series(D[1], _pad(Dr, off))
            K[2] = add_series(K.get(2, {}), _pad(Kr, off))
            f[2] = add_series(f.get(2, {}), _pad(fr, off))
    i, j = nodes
    dofs = np.concatenate([6 * i + np.arange(6), 6 * j + np.arange(6)])
    return SpeedTerm(dofs=dofs, M=M, D=D, K=K, f=f)
