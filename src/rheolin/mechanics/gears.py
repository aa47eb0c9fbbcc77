"""Gear meshes (spur and helical) as a time-varying spring along the line of action.

The relative approach of the two flanks along the unit normal ``n`` at the contact point ``P``
is ``delta = w^T q`` with, for pinion node ``a`` and gear node ``b`` (docs/rotating-bodies.md)::

    w = ( n, (P - x_a) x n, -n, -(P - x_b) x n )

The mesh adds ``K += k(t) w w^T``, ``D += c w w^T`` and ``f += k(t) e(t) w`` (static
transmission error ``e``: the potential is ``k (delta - e)^2 / 2``). ``k(t)`` and ``e(t)`` are
Fourier series in the mesh frequency ``W_m = z_pinion |W_pinion|``; their product is a
convolution of the coefficient sequences.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ModelError
from ._term import Term
from .items import positive
from .rolling import MeshLoadLaw

__all__ = [
    "gear_mesh_term",
    "line_of_action",
    "mesh_convolve",
    "mesh_record",
    "rectangular_wave_coefficients",
]


def rectangular_wave_coefficients(
    contact_ratio: float,
    single_stiffness: float,
    double_stiffness: float,
    n_harmonics: int,
    phase: float = 0.0,
) -> dict[int, complex]:
    """Exact Fourier coefficients of a single/double-contact rectangular mesh stiffness.

    Over one mesh period ``T`` two tooth pairs are in contact for the fraction
    ``d = contact_ratio - 1`` (stiffness ``double_stiffness``), one pair for the rest. With the
    double-contact interval centred at ``t = phase / W_m``::

        k_0 = k_s + (k_d - k_s) d,   k_j = (k_d - k_s) sin(pi j d) / (pi j) exp(-i j phase)

    Parameters
    ----------
    contact_ratio
        Transverse contact ratio, ``1 <= contact_ratio <= 2``.
    single_stiffness, double_stiffness
        Mesh stiffness with one and two tooth pairs in contact [N/m].
    n_harmonics
        Keep mesh harmonics ``|j| <= n_harmonics``.
    phase
        Mesh phase [rad of the mesh cycle] of the centre of the double-contact interval.

    Returns
    -------
    dict
        Two-sided ``{j: k_j}`` in units of the mesh frequency.

    Examples
    --------
    >>> c = rectangular_wave_coefficients(1.5, 1.0, 2.0, 2)
    >>> c[0], round(c[1].real, 12), round(c[2].real, 12)
    (1.5, 0.31831, 0.0)
    """
    if not 1.0 <= contact_ratio <= 2.0:
        raise ModelError(f"`contact_ratio` must lie in [1, 2], got {contact_ratio!r}")
    if isinstance(n_harmonics, bool) or not isinstance(n_harmonics, int) or n_harmonics < 0:
        raise ModelError(f"`n_harmonics` must be a non-negative integer, got {n_harmonics!r}")
    d = contact_ratio - 1.0
    jump = double_stiffness - single_stiffness
    out: dict[int, complex] = {0: single_stiffness + jump * d}
    for j in range(1, n_harmonics + 1):
        c = jump * np.sin(np.pi * j * d) / (np.pi * j) * np.exp(-1j * j * phase)
        out[j] = complex(c)
        out[-j] = complex(np.conj(c))
    return out


def mesh_convolve(a: Mapping[int, complex], b: Mapping[int, complex]) -> dict[int, complex]:
    """Fourier coefficients of the product of two series: ``(ab)_n = sum_j a_j b_{n-j}``.

    >>> mesh_convolve({0: 2.0, 1: 0.5, -1: 0.5}, {1: 1j, -1: -1j})
    {1: 2j, -1: -2j, 2: 0.5j, 0: 0j, -2: -0.5j}
    """
    out: dict[int, complex] = {}
    for i, x in a.items():
        for j, y in b.items():
            out[i + j] = out.get(i + j, 0) + x * y
    return out


def line_of_action(
    position_a: ArrayLike,
    position_b: ArrayLike,
    axis: ArrayLike,
    base_radius_a: float,
    base_radius_b: float,
    pressure_angle: float,
    helix_angle: float = 0.0,
    side: int = 1,
    center_direction: ArrayLike | None = None,
) -> np.ndarray:
    """The 12-vector ``w`` with ``delta = w^T (q_a, q_b)`` for an external parallel-axis pair.

    Parameters
    ----------
    position_a, position_b
        Node positions of pinion and gear [m].
    axis
        Common direction of the two (parallel) axes.
    base_radius_a, base_radius_b
        Base circle radii [m].
    pressure_angle
        Transverse working pressure angle [rad].
    helix_angle
        Helix angle at the pitch circle [rad]; its sign selects the direction of the axial
        force component (0: spur).
    side
        +1: the pinion flank that pushes the gear when the pinion turns positively about
        ``axis``; -1 the opposite flank.
    center_direction
        Direction from pinion to gear centre; needed only when the two nodes lie on one axis
        (then the centre distance is ``(r_ba + r_bb) / cos(pressure_angle)``).

    Examples
    --------
    Spur pair along x, pinion turning about +z: torsional entries are the base radii.

    >>> w = line_of_action([0, 0, 0], [0.1, 0, 0], [0, 0, 1], 0.03, 0.06, np.radians(20))
    >>> np.round(w[[5, 11]], 6)
    array([0.03, 0.06])
    """
    if side not in (1, -1):
        raise ModelError(f"`side` must be +1 or -1, got {side!r}")
    for name, r in (("base_radius_a", base_radius_a), ("base_radius_b", base_radius_b)):
        if not r > 0:
            raise ModelError(f"`{name}` must be > 0 [m], got {r!r}")
    if not 0 <= pressure_angle < np.pi / 2:
        raise ModelError(f"`pressure_angle` must lie in [0, pi/2) [rad], got {pressure_angle!r}")
    e = np.asarray(axis, dtype=float)
    e = e / np.linalg.norm(e)
    xa, xb = np.asarray(position_a, float), np.asarray(position_b, float)
    d = (xb - xa) - e * np.dot(xb - xa, e)
    dist = np.linalg.norm(d)
    if center_direction is not None or dist < 1e-12:
        if center_direction is None:
            raise ModelError("`center_direction` is required when both gear nodes lie on one axis")
        d = np.asarray(center_direction, float)
        d = d - e * np.dot(d, e)
        if np.linalg.norm(d) == 0:
            raise ModelError("`center_direction` must not be parallel to `axis`")
        if dist < 1e-12:
            dist = (base_radius_a + base_radius_b) / np.cos(pressure_angle)
    ex = d / np.linalg.norm(d)
    ey = np.cross(e, ex)
    t = np.sin(pressure_angle) * ex + side * np.cos(pressure_angle) * ey
    beta_b = np.arctan(np.tan(helix_angle) * np.cos(pressure_angle))
    n = np.cos(beta_b) * t + np.sin(beta_b) * side * e
    P = xa + ex * dist * base_radius_a / (base_radius_a + base_radius_b)
    # gear centre: the gear node, moved out to the centre distance when nodes share an axis
    xb_centre = xb + ex * (dist - np.linalg.norm((xb - xa) - e * np.dot(xb - xa, e)))
    ra, rb = P - xa, P - xb_centre
    return np.concatenate([n, np.cross(ra, n), -n, -np.cross(rb, n)])


def gear_mesh_term(
    dofs_a: ArrayLike,
    dofs_b: ArrayLike,
    w: np.ndarray,
    mesh_harmonic: int,
    stiffness: Mapping[int, complex] | float,
    damping: float = 0.0,
    transmission_error: Mapping[int, complex] | None = None,
) -> Term:
    """The mesh contribution ``k(t) w w^T``, ``c w w^T``, ``k(t) e(t) w`` as a Term.

    Parameters
    ----------
    dofs_a, dofs_b
        Global DOFs of pinion and gear node (six each).
    w
        Line-of-action vector from :func:`line_of_action` (length 12).
    mesh_harmonic
        Mesh frequency in units of ``w1`` (``z_pinion |s_pinion|``).
    stiffness
        Mean stiffness [N/m], or two-sided coefficients ``{j: k_j}`` in mesh harmonics ``j``
        (missing ``-j`` filled as conjugates).
    damping
        Mesh damping [N s/m], constant.
    transmission_error
        Two-sided coefficients ``{j: e_j}`` [m] of the static transmission error.

    Examples
    --------
    ``k(t) = k (1 + eps cos(W_m t))`` with mesh harmonic 3:

    >>> w = np.zeros(12); w[5], w[11] = -0.03, -0.06
    >>> t = gear_mesh_term(range(6), range(6, 12), w, 3, {0: 1e8, 1: 0.1e8 / 2})
    >>> sorted(t.K), float(t.K[3][5, 11].real)
    ([-3, 0, 3], 9000.0)
    """
    if isinstance(mesh_harmonic, bool) or not isinstance(mesh_harmonic, int | np.integer):
        raise ModelError(f"`mesh_harmonic` must be an integer, got {mesh_harmonic!r}")
    w = np.asarray(w, dtype=float).ravel()
    if w.shape != (12,):
        raise ModelError(f"`w` must have 12 entries, got {w.shape}")
    k = (
        _two_sided(stiffness, "stiffness")
        if isinstance(stiffness, Mapping)
        else {0: float(stiffness)}
    )
    if np.real(k.get(0, 0)) < 0:
        raise ModelError(f"`stiffness` mean must be >= 0 [N/m], got {k.get(0)}")
    if damping < 0:
        raise ModelError(f"`damping` must be >= 0 [N s/m], got {damping!r}")
    m = int(mesh_harmonic)
    ww = np.outer(w, w)
    K: dict[int, np.ndarray] = {}
    for j, kj in k.items():
        if kj != 0:
            K[j * m] = K.get(j * m, 0) + (kj * ww if j else np.real(kj) * ww)
    D = {0: damping * ww} if damping else {}
    f: dict[int, np.ndarray] = {}
    if transmission_error:
        for j, v in mesh_convolve(k, _two_sided(transmission_error, "transmission_error")).items():
            if v != 0:
                f[j * m] = (v.real if j == 0 else v) * w
    dofs = np.concatenate([np.asarray(dofs_a), np.asarray(dofs_b)]).astype(np.int64)
    return Term(dofs, K=K, D=D, f=f)


def _two_sided(coeffs: Mapping[int, complex], field: str) -> dict[int, complex]:
    out: dict[int, complex] = {}
    for j, v in coeffs.items():
        if isinstance(j, bool) or not isinstance(j, int | np.integer):
            raise ModelError(f"`{field}` keys must be integer mesh harmonics, got {j!r}")
        out[int(j)] = complex(v)
    if 0 in out and abs(out[0].imag) > 1e-12 * max(abs(out[0]), 1e-300):
        raise ModelError(f"`{field}[0]` must be real (mean of a real signal), got {out[0]}")
    for j in [j for j in out if j != 0]:
        if -j not in out:
            out[-j] = np.conj(out[j])
        elif abs(out[-j] - np.conj(out[j])) > 1e-12 * max(abs(out[j]), 1e-300):
            raise ModelError(f"`{field}[{-j}]` must equal conj(`{field}[{j}]`) (real signal)")
    if 0 in out:
        out[0] = complex(out[0].real)
    return out


def mesh_record(
    module: float,
    pressure_angle: float,
    helix_angle: float,
    stiffness: float | dict[int, complex] | None,
    contact_ratio: float | None,
    single_stiffness: float | None,
    double_stiffness: float | None,
    stiffness_harmonics: int,
    damping: float,
    transmission_error: dict[int, complex] | None,
    side: int,
    center_direction: Sequence[float] | None,
    load_law: str | None,
    face_width: float | None,
    load_forces: Sequence[float] | None,
    load_stiffness: Sequence[float] | None,
) -> dict[str, Any]:
    """The geometry, stiffness function and load law of a mesh, checked, as the model's mesh
    table holds them (``Model.add_gear_mesh`` names the arguments): the stiffness given, or
    the rectangular wave of the contact ratio and the two tooth-pair levels.

    >>> g = mesh_record(0.003, 0.35, 0.0, None, 1.5, 2e8, 3e8, 4, 0.0, None, 1, None,
    ...                 None, None, None, None)
    >>> round(float(np.real(g["stiffness"][0])) / 1e8, 6)
    2.5
    """
    if stiffness is None:
        if None in (contact_ratio, single_stiffness, double_stiffness):
            raise ModelError(
                "give `stiffness`, or `contact_ratio`, `single_stiffness` and "
                "`double_stiffness` (rectangular wave)"
            )
        assert contact_ratio is not None and single_stiffness is not None
        assert double_stiffness is not None
        stiffness = rectangular_wave_coefficients(
            contact_ratio, single_stiffness, double_stiffness, stiffness_harmonics
        )
    positive(module, "module")
    mesh_law = None
    if load_law is not None:
        mesh_law = MeshLoadLaw(
            law=load_law,
            face_width=float(face_width or 0.0),
            forces=None if load_forces is None else np.asarray(load_forces, float),
            stiffness=None if load_stiffness is None else np.asarray(load_stiffness, float),
        )
    return dict(
        module=float(module),
        pressure_angle=float(pressure_angle),
        helix_angle=float(helix_angle),
        stiffness=stiffness,
        damping=float(damping),
        transmission_error=transmission_error,
        side=side,
        center_direction=center_direction,
        load_law=mesh_law,
    )
