"""Conical (tapered) Timoshenko shaft element of a circular tube, 2 nodes x 6 DOF.

The outer and inner radii vary linearly from the left node (``r_o``, ``r_i``) to the right
node; area and second moment are then polynomials in ``xi = x / L``:

    A(xi)  = A_l  (1 + a1 xi + b1 xi^2)
    I(xi)  = I_l  (1 + a2 xi + b2 xi^2 + g xi^3 + d xi^4)

with ``a1 = 2 pi (r_o dr_o - r_i dr_i) / A_l``, ``b1 = pi (dr_o^2 - dr_i^2) / A_l``,
``a2 = pi (r_o^3 dr_o - r_i^3 dr_i) / I_l``, ``b2 = 3 pi (r_o^2 dr_o^2 - r_i^2 dr_i^2) / (2 I_l)``,
``g = pi (r_o dr_o^3 - r_i dr_i^3) / I_l``, ``d = pi (dr_o^4 - dr_i^4) / (4 I_l)``. Bending
mass, rotary inertia, gyroscopic and stiffness matrices are the closed-form integrals of the
cubic Timoshenko shape functions over this variation (Genta & Gugliotta, *A conical element for
finite element rotor dynamics*, J. Sound Vib. 120 (1988) 175-182), with the shear parameter
``phi = 12 E I_m / (kappa G A_m L^2)`` of the mid-span section and Cowper's shear factor of the
mean diameters. Axial and torsional parts use the mean area and polar moment. These are the
matrices ROSS (``ross.ShaftElement``) uses, so an imported ROSS rotor is reproduced exactly;
for ``left == right`` they reduce to the uniform element of :mod:`rheolin.mechanics.beam`
(tests/mechanics/test_conical.py checks both).

DOF order per node: ``(ux, uy, uz, phix, phiy, phiz)`` with the element along local ``z``.
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError
from .beam import BeamMatrices, local_axes

__all__ = ["conical_body_matrices", "conical_local_matrices"]


def _bending(v: dict[str, float]) -> np.ndarray:
    """12x12 bending block of the symmetric pattern shared by M, Mr and K (ux-phiy and
    uy-phix planes), from the eight coefficients ``t1 (u1u1), t2 (u1 r1), t3 (u1u2),
    t4 (u1 r2), t5 (r1r1), t6 (r1 u2), t7 (r1r2), t8 (u2u2), t9 (u2 r2), t10 (r2r2)``.

    In the x-z plane (ux, phiy) the rotation is ``phiy = +du/dz``; in the y-z plane
    (uy, phix) it is ``phix = -dv/dz``, hence the sign flips of the rotation rows.
    """
    X = np.zeros((12, 12))
    # x-z plane: (ux1, phiy1, ux2, phiy2) = dofs (0, 4, 6, 10)
    p = [0, 4, 6, 10]
    t = v
    P = np.array(
        [
            [t["uu11"], t["ur11"], t["uu12"], t["ur12"]],
            [t["ur11"], t["rr11"], t["ru12"], t["rr12"]],
            [t["uu12"], t["ru12"], t["uu22"], t["ur22"]],
            [t["ur12"], t["rr12"], t["ur22"], t["rr22"]],
        ]
    )
    X[np.ix_(p, p)] = P
    # y-z plane: (uy1, phix1, uy2, phix2) = dofs (1, 3, 7, 9); phix = -dv/dz
    q = [1, 3, 7, 9]
    S = np.diag([1.0, -1.0, 1.0, -1.0])
    X[np.ix_(q, q)] = S @ P @ S
    return X


def conical_local_matrices(
    length: float,
    outer_left: float,
    inner_left: float,
    outer_right: float,
    inner_right: float,
    E: float,
    G: float,
    density: float,
    shear: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(M, K, G)`` (12x12) of a conical tube along local ``z`` (see the module docstring).

    ``G`` is the gyroscopic matrix per unit spin speed about ``+z`` (``D = W G``).

    Examples
    --------
    A uniform element: the translational mass sums to ``rho A L`` in each direction.

    >>> M, K, G = conical_local_matrices(0.5, 0.1, 0.0, 0.1, 0.0, 2e11, 8e10, 7800.0)
    >>> m = 7800.0 * np.pi * 0.1**2 / 4 * 0.5
    >>> bool(np.isclose(M[np.ix_([0, 6], [0, 6])].sum(), m))
    True
    """
    L = float(length)
    roj, rij, rok, rik = (
        float(outer_left) / 2,
        float(inner_left) / 2,
        float(outer_right) / 2,
        float(inner_right) / 2,
    )
    if not (L > 0 and np.isfinite(L)):
        raise ModelError(f"`length` must be finite and > 0, got {length!r}")
    if not (0 <= rij < roj and 0 <= rik < rok):
        raise ModelError(
            "conical element: need 0 <= inner < outer diameter at both ends, got "
            f"left {outer_left!r}/{inner_left!r}, right {outer_right!r}/{inner_right!r}"
        )
    A_l = np.pi * (roj**2 - rij**2)
    A_r = np.pi * (rok**2 - rik**2)
    I_l = np.pi * (roj**4 - rij**4) / 4
    I_r = np.pi * (rok**4 - rik**4) / 4
    dro, dri = rok - roj, rik - rij
    a1 = 2 * np.pi * (roj * dro - rij * dri) / A_l
    b1 = np.pi * (dro**2 - dri**2) / A_l
    a2 = np.pi * (roj**3 * dro - rij**3 * dri) / I_l
    b2 = 3 * np.pi * (roj**2 * dro**2 - rij**2 * dri**2) / (2 * I_l)
    g = np.pi * (roj * dro**3 - rij * dri**3) / I_l
    d = np.pi * (dro**4 - dri**4) / (4 * I_l)
    A_m = A_l * (1 + a1 / 2 + b1 / 4)
    I_m = I_l * (1 + a2 / 2 + b2 / 4 + g / 8 + d / 16)
    phi = 0.0
    if shear:
        nu = E / (2 * G) - 1
        r = (rij + rik) / (roj + rok)
        r2 = r * r
        r12 = (1 + r2) ** 2
        kappa = 6 * r12 * (1 + nu) / (r12 * (7 + 6 * nu) + r2 * (20 + 12 * nu))  # Cowper
        phi = 12 * E * I_m / (G * kappa * A_m * L**2)
    p, p2 = phi, phi**2

    # translational mass, times rho A_l L / (1260 (1 + phi)^2)
    def lin(c0: tuple[float, ...], c1: tuple[float, ...], c2: tuple[float, ...]) -> float:
        return sum(w * (c[0] + c[1] * p + c[2] * p2) for w, c in ((1.0, c0), (a1, c1), (b1, c2)))

    m1 = lin((468, 882, 420), (108, 210, 105), (38, 78, 42))
    m2 = lin((66, 115.5, 52.5), (21, 40.5, 21), (8.5, 18, 10.5)) * L
    m3 = lin((162, 378, 210), (81, 189, 105), (46, 111, 63))
    m4 = lin((39, 94.5, 52.5), (18, 40.5, 21), (9.5, 21, 10.5)) * L
    m5 = lin((12, 21, 10.5), (4.5, 9, 5.25), (2, 4.5, 3)) * L**2
    m6 = lin((39, 94.5, 52.5), (21, 54, 31.5), (12.5, 34.5, 21)) * L
    m7 = lin((9, 21, 10.5), (4.5, 10.5, 5.25), (2.5, 6, 3)) * L**2
    m8 = lin((468, 882, 420), (360, 672, 315), (290, 540, 252))
    m9 = lin((66, 115.5, 52.5), (45, 75, 31.5), (32.5, 52.5, 21)) * L
    m10 = lin((12, 21, 10.5), (7.5, 12, 5.25), (5, 7.5, 3)) * L**2
    Mt = _bending(
        dict(
            uu11=m1,
            ur11=m2,
            uu12=m3,
            ur12=-m4,
            rr11=m5,
            ru12=m6,
            rr12=-m7,
            uu22=m8,
            ur22=-m9,
            rr22=m10,
        )
    ) * (density * A_l * L / (1260 * (1 + p) ** 2))

    # rotary inertia (and, with the factor 2, the gyroscopic matrix), times rho I_l / (210 L)
    def quart(c: tuple[tuple[float, ...], ...]) -> float:
        return sum(
            w * (k[0] + k[1] * p + k[2] * p2) for w, k in zip((1.0, a2, b2, g, d), c, strict=True)
        )

    r11 = 252 + 126 * a2 + 72 * b2 + 45 * g + 30 * d
    r12 = quart(((21, -105, 0), (21, -42, 0), (15, -21, 0), (10.5, -12, 0), (7.5, -7.5, 0))) * L
    r13 = quart(((21, -105, 0), (0, -63, 0), (-6, -42, 0), (-7.5, -30, 0), (-7.5, -22.5, 0))) * L
    r14 = quart(((28, 35, 70), (7, -7, 17.5), (4, -7, 7), (2.75, -5, 3.5), (2, -3.5, 2))) * L**2
    r15 = (
        quart(((7, 35, -35), (3.5, 17.5, -17.5), (3, 10.5, -10.5), (2.75, 7, -7), (2.5, 5, -5)))
        * L**2
    )
    r16 = (
        quart(((28, 35, 70), (21, 42, 52.5), (18, 42, 42), (16.25, 40, 35), (15, 37.5, 30))) * L**2
    )
    rot = dict(
        uu11=r11,
        ur11=r12,
        uu12=-r11,
        ur12=r13,
        rr11=r14,
        ru12=-r12,
        rr12=-r15,
        uu22=r11,
        ur22=-r13,
        rr22=r16,
    )
    scale_r = density * I_l / (210 * L * (1 + p) ** 2)
    Mr = _bending(rot) * scale_r

    # gyroscopic: G = 2 * (x-z / y-z cross coupling of the rotary pattern), skew-symmetric
    R4 = np.array(
        [
            [r11, r12, -r11, r13],
            [r12, r14, -r12, -r15],
            [-r11, -r12, r11, -r13],
            [r13, -r15, -r13, r16],
        ]
    )
    Gy = np.zeros((12, 12))
    xz, yz = [0, 4, 6, 10], [1, 3, 7, 9]
    S = np.diag([1.0, -1.0, 1.0, -1.0])
    Gy[np.ix_(xz, yz)] = R4 @ S
    Gy[np.ix_(yz, xz)] = -S @ R4
    Gy *= 2 * scale_r

    # bending stiffness, times E / (L^3 (1 + phi)^2)
    k1 = 1260 + 630 * a2 + 504 * b2 + 441 * g + 396 * d
    sh = p * (105 * a2 + 105 * b2 + 94.5 * g + 84 * d)
    k2 = (630 + 210 * a2 + 147 * b2 + 126 * g + 114 * d - sh) * L
    k3 = (630 + 420 * a2 + 357 * b2 + 315 * g + 282 * d + sh) * L
    k4 = (
        quart(((420, 210, 105), (105, 0, 52.5), (56, -35, 35), (42, -42, 26.25), (36, -42, 21)))
        * L**2
    )
    k5 = (
        quart(
            (
                (210, -210, -105),
                (105, -105, -52.5),
                (91, -70, -35),
                (84, -52.5, -26.25),
                (78, -42, -21),
            )
        )
        * L**2
    )
    k6 = (
        quart(
            ((420, 210, 105), (315, 210, 52.5), (266, 175, 35), (231, 147, 26.25), (204, 126, 21))
        )
        * L**2
    )
    K1 = _bending(
        dict(
            uu11=k1,
            ur11=k2,
            uu12=-k1,
            ur12=k3,
            rr11=k4,
            ru12=-k2,
            rr12=k5,
            uu22=k1,
            ur22=-k3,
            rr22=k6,
        )
    ) * (I_l / 105)
    k7 = 12 + 6 * a1 + 4 * b1
    k8 = (6 + 3 * a1 + 2 * b1) * L
    k9 = (3 + 1.5 * a1 + b1) * L**2
    K2 = _bending(
        dict(
            uu11=k7,
            ur11=k8,
            uu12=-k7,
            ur12=k8,
            rr11=k9,
            ru12=-k8,
            rr12=k9,
            uu22=k7,
            ur22=-k8,
            rr22=k9,
        )
    ) * (I_m * p * A_l / A_m)
    K = (K1 + K2) * (E / (L**3 * (1 + p) ** 2))

    M = Mt + Mr
    Ae, Je = (A_l + A_r) / 2, I_l + I_r  # mean area, mean polar moment (= 2 x mean I)
    two = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6
    bar = np.array([[1.0, -1.0], [-1.0, 1.0]])
    ax, tw = [2, 8], [5, 11]
    M[np.ix_(ax, ax)] += density * Ae * L * two
    M[np.ix_(tw, tw)] += density * Je * L * two
    K[np.ix_(ax, ax)] += E * Ae / L * bar
    K[np.ix_(tw, tw)] += G * Je / L * bar
    return M, K, Gy


def conical_body_matrices(
    length: float,
    diameters: tuple[float, float, float, float],
    E: float,
    G: float,
    density: float,
    direction: object,
    damping_beta: float = 0.0,
) -> BeamMatrices:
    """:func:`conical_local_matrices` in global axes for an element along ``direction``
    (``diameters = (outer_left, inner_left, outer_right, inner_right)``).

    >>> b = conical_body_matrices(0.2, (0.05, 0.0, 0.03, 0.0), 2e11, 8e10, 7800.0, [1, 0, 0])
    >>> bool(np.allclose(b.K, b.K.T)), bool(np.allclose(b.gyroscopic, -b.gyroscopic.T))
    (True, True)
    """
    M, K, Gy = conical_local_matrices(length, *diameters, E, G, density)
    x, y, z = local_axes(direction)
    Q = np.column_stack([y, z, x])  # local (x, y, z-along-element) -> global
    T = np.kron(np.eye(4), Q)
    Mg, Kg, Gg = (T @ X @ T.T for X in (M, K, Gy))
    return BeamMatrices(Mg, Kg, damping_beta * Kg, Gg, None)
