"""The speed terms of a whole planetary set: planets, their bearings and their meshes.

The set (:class:`~rheolin.mechanics.planetary.PlanetaryGeometry`) sits on the carrier's axis;
its sun, ring and carrier are nodes of ordinary bodies and every planet is a
node of its own in the carrier's axes (:mod:`rheolin.mechanics.carrier_frame` says why). Each
planet contributes its inertia, its bearing on the carrier's pin and a sun and a ring mesh,
phased by its angle (:func:`~rheolin.mechanics.planetary.mesh_phases`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import ModelError
from ._term import SpeedTerm
from .carrier_frame import (
    carried_vector,
    centripetal_load,
    planet_bearing_term,
    planet_inertia_term,
    planet_mesh_term,
)
from .planetary import PlanetaryGeometry, mesh_phases, phased

__all__ = ["MeshFamily", "PlanetData", "SetMesh", "SetNodes", "planetary_speed_terms"]


@dataclass(frozen=True)
class MeshFamily:
    """The sun-planet (or ring-planet) meshes: planet 0's stiffness ``{j: k_j}`` and static
    transmission error ``{j: e_j}`` over mesh harmonics (the other planets' are phased), and
    the mesh damping [N s/m]."""

    stiffness: Mapping[int, complex]
    damping: float = 0.0
    transmission_error: Mapping[int, complex] | None = None


@dataclass(frozen=True)
class PlanetData:
    """What every planet of a set shares, and the pin errors of each.

    Attributes
    ----------
    mass, inertia
        Planet mass [kg] and inertia about its centre [kg m^2] (3 principal values about the
        planet's radial, tangential and axial directions, or 3x3 in those axes).
    bearing_stiffness, bearing_damping
        6x6 on the planet's motion relative to its pin, in the planet's radial, tangential and
        axial axes (rows and columns ``ur, ut, ua, phir, phit, phia``); no stiffness about the
        axis (the planet turns on its bearing).
    pin_errors
        Per planet, the pin's position error (radial, tangential[, axial]) [m]; empty: none.
    """

    mass: float
    inertia: np.ndarray
    bearing_stiffness: np.ndarray
    bearing_damping: np.ndarray | None = None
    pin_errors: tuple[np.ndarray, ...] = field(default_factory=tuple)

    def __post_init__(self) -> None:
        K = np.asarray(self.bearing_stiffness, dtype=float)
        if K.shape != (6, 6) or not np.all(np.isfinite(K)):
            raise ModelError(f"`planet_bearing` stiffness must be 6x6 and finite, got {K.shape}")
        if K[5, 5] != 0 or np.any(K[5, :5]) or np.any(K[:5, 5]):
            raise ModelError(
                "`planet_bearing` stiffness: a planet turns on its bearing, so it has no "
                "stiffness about the axis (phiz)"
            )
        if not np.allclose(K, K.T, rtol=1e-12, atol=0):
            raise ModelError("`planet_bearing` stiffness must be symmetric")


@dataclass(frozen=True)
class SetNodes:
    """Where the set is in the model: the six DOFs and the position of the sun, ring and
    carrier nodes, each planet's six DOFs, and the set's axis and angle reference."""

    sun: tuple[np.ndarray, np.ndarray]
    ring: tuple[np.ndarray, np.ndarray]
    carrier: tuple[np.ndarray, np.ndarray]
    planets: Sequence[np.ndarray]
    axis: np.ndarray
    reference: np.ndarray


@dataclass(frozen=True)
class SetMesh:
    """One mesh of a set, for outputs: the mesh deflection ``delta(t) = sum_k g_k^T q_dofs
    exp(i k w1 t)``, the mesh harmonic and the mesh's term (at power 0)."""

    dofs: np.ndarray
    vector: dict[int, np.ndarray]
    harmonic: int
    term: SpeedTerm


def _local_axes(radial: np.ndarray, tangential: np.ndarray, axis: np.ndarray) -> np.ndarray:
    T = np.column_stack([radial, tangential, axis])
    return np.kron(np.eye(2), T)


def planetary_speed_terms(
    name: str,
    geometry: PlanetaryGeometry,
    nodes: SetNodes,
    planet: PlanetData,
    sun_mesh: MeshFamily,
    ring_mesh: MeshFamily,
    spins: Mapping[str, int],
    mesh_harmonic: int,
    flank: int = 1,
    ring_phase: float = 0.0,
    member_spins: Mapping[str, int] | None = None,
    inertia: bool = True,
) -> tuple[list[SpeedTerm], dict[str, SetMesh]]:
    """Every planet's inertia, bearing and meshes as speed terms.

    Parameters
    ----------
    name
        The set's name (mesh names are ``{name}.sun{n}`` and ``{name}.ring{n}``).
    geometry, nodes, planet, sun_mesh, ring_mesh
        The set.
    spins
        Spin harmonics (``W = s w1``) of ``"sun"``, ``"ring"``, ``"carrier"`` and ``"planet"``
        (absolute).
    mesh_harmonic
        ``z_s |s_sun - s_carrier|``.
    flank
        +1: the sun pushes the planets in the direction it turns relative to the carrier.
    ring_phase
        Phase of planet 0's ring mesh after its sun mesh [rad of the mesh cycle].
    member_spins
        How the axes of the ``"sun"``, ``"ring"`` and ``"carrier"`` nodes' DOFs turn relative
        to the carrier (spin harmonics): 0 for a member written in this carrier's axes (the
        default for all three), ``s_carrier`` for an inertial one, ``s_carrier - s_other``
        for one written in another coaxial set's carrier axes.
    inertia
        Include the planets' inertia (False: the model's planet bodies carry it; the load
        that keeps them on their orbit is included either way).

    Returns
    -------
    terms, meshes
        The speed terms, and the meshes by name.
    """
    if len(nodes.planets) != geometry.planets:
        raise ModelError(f"{geometry.planets} planets need as many planet nodes")
    errors = planet.pin_errors
    if errors and len(errors) != geometry.planets:
        raise ModelError(f"`pin_errors` needs one entry per planet ({geometry.planets})")
    s_c = int(spins["carrier"])
    turn = {"sun": 0, "ring": 0, "carrier": 0, **(member_spins or {})}
    rel = int(np.sign(spins["sun"] - s_c))
    sigma = flank * (rel or 1)  # the flank in contact, in the carrier's sense of rotation
    x_s, x_r, x_c = nodes.sun[1], nodes.ring[1], nodes.carrier[1]
    contacts = geometry.contacts(nodes.axis, nodes.reference, x_s, x_s, x_r, sigma)
    gamma_s, gamma_r = mesh_phases(geometry, rel, ring_phase)
    e = nodes.axis
    terms: list[SpeedTerm] = []
    meshes: dict[str, SetMesh] = {}
    for n, (c, dofs) in enumerate(zip(contacts, nodes.planets, strict=True)):
        T = _local_axes(c.radial, c.tangential, e)
        Jl = np.asarray(planet.inertia, dtype=float)
        J = T[:3, :3] @ (np.diag(Jl) if Jl.shape == (3,) else Jl) @ T[:3, :3].T
        if inertia:
            terms.append(
                planet_inertia_term(dofs, planet.mass, J, e, spins["planet"], s_c, c.position - x_c)
            )
        else:
            terms.append(centripetal_load(dofs, planet.mass, e, s_c, c.position - x_c))
        KB = T @ np.asarray(planet.bearing_stiffness, dtype=float) @ T.T
        DB = None if planet.bearing_damping is None else T @ planet.bearing_damping @ T.T
        err = None
        if errors:
            local = np.zeros(6)
            given = np.asarray(errors[n], dtype=float).ravel()
            local[: given.size] = given
            err = T @ local
        terms.append(
            planet_bearing_term(
                nodes.carrier[0], dofs, c.position - x_c, e, turn["carrier"], KB, DB, err
            )
        )
        for kind, member, fam, w, gamma in (
            ("sun", nodes.sun[0], sun_mesh, c.sun, gamma_s[n]),
            ("ring", nodes.ring[0], ring_mesh, c.ring, gamma_r[n]),
        ):
            te = fam.transmission_error
            term = planet_mesh_term(
                member,
                dofs,
                w,
                e,
                turn[kind],
                mesh_harmonic,
                phased(fam.stiffness, gamma),
                fam.damping,
                None if te is None else phased(te, gamma),
            )
            terms.append(term)
            meshes[f"{name}.{kind}{n}"] = SetMesh(
                term.dofs, carried_vector(w, e, turn[kind]), mesh_harmonic, term
            )
    return terms, meshes
