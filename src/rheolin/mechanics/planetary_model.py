"""The planetary-set table of a model: ``Model.add_planetary`` and the record it keeps.

A set joins three bodies of the model (its sun, ring and carrier: shafts, rigid or condensed
bodies, each connectable to anything else) and adds one body per planet (kind ``"planet"``,
one node at the planet's centre at ``t = 0``, written in the carrier's axes). The checks of
the set's geometry are in :mod:`rheolin.mechanics.planetary`, its terms in
:mod:`rheolin.mechanics.planetary_terms`, its speeds in :mod:`rheolin.mechanics.willis`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ModelError
from .gears import rectangular_wave_coefficients
from .items import Body, ModelData, recorded
from .joints import expand_matrix
from .planetary import PlanetaryGeometry, check_members, equal_spacing
from .planetary_terms import MeshFamily, PlanetData
from .rigid import RigidNode, disk, unbalance_reference
from .sections import material_constants
from .willis import SpeedConstraint, set_constraints

__all__ = ["FRAMES", "PlanetarySet", "PlanetaryTable", "planet_name"]

#: Where a set's sun, ring and carrier bodies are written: in the carrier's axes (the set is
#: then time-invariant but for its meshes: exact averaged modes) or in global axes.
FRAMES = ("carrier", "inertial")
_MESH_KEYS = {
    "stiffness", "contact_ratio", "single_stiffness", "double_stiffness", "stiffness_harmonics",
    "damping", "transmission_error",
}  # fmt: skip
_PLANET_KEYS = {"mass", "inertia", "outer_diameter", "width", "inner_diameter", "density",
                "material"}  # fmt: skip
_BEARING_KEYS = {"stiffness", "damping", "components"}
#: A planet bearing's default components, in the planet's radial, tangential, axial axes: all
#: but the rotation about the axis (the planet turns on it).
BEARING_COMPONENTS = ("ux", "uy", "uz", "phix", "phiy")


def planet_name(set_name: str, n: int) -> str:
    """The body name of planet ``n`` of a set.

    >>> planet_name("stage1", 2)
    'stage1.planet2'
    """
    return f"{set_name}.planet{n}"


@dataclass(frozen=True)
class PlanetarySet:
    """A set as the model keeps it (every field checked)."""

    name: str
    geometry: PlanetaryGeometry
    sun: tuple[str, int]
    ring: tuple[str, int]
    carrier: tuple[str, int]
    planets: tuple[str, ...]
    planet: PlanetData
    sun_mesh: MeshFamily
    ring_mesh: MeshFamily
    reference: np.ndarray
    side: int = 1
    ring_phase: float = 0.0
    frame: str = "carrier"

    def constraints(self) -> list[SpeedConstraint]:
        """The Willis constraints of its planets' sun and ring meshes."""
        g = self.geometry
        return set_constraints(
            f"planetary set {self.name!r}",
            self.sun[0],
            self.ring[0],
            self.carrier[0],
            self.planets,
            (g.sun_teeth, g.planet_teeth, g.ring_teeth),
        )


def _keys(table: Mapping[str, Any] | None, allowed: set[str], field: str) -> dict[str, Any]:
    if table is None:
        raise ModelError(f"`{field}` is required (a table with keys {sorted(allowed)})")
    if not isinstance(table, Mapping):
        raise ModelError(f"`{field}` must be a table with keys {sorted(allowed)}, got {table!r}")
    bad = sorted(set(table) - allowed)
    if bad:
        raise ModelError(f"`{field}.{bad[0]}` is not a key of it; allowed: {sorted(allowed)}")
    return dict(table)


def mesh_family(table: Mapping[str, Any] | None, field: str) -> MeshFamily:
    """A sun or ring mesh table: ``stiffness`` (mean or ``{j: k_j}``) or the rectangular wave
    of ``contact_ratio``, ``single_stiffness``, ``double_stiffness`` (``stiffness_harmonics``),
    ``damping``, ``transmission_error`` ``{j: e_j}`` (planet 0's; the others are phased).

    >>> mesh_family({"stiffness": 5e8, "damping": 100.0}, "sun_mesh").stiffness
    {0: (500000000+0j)}
    """
    t = _keys(table, _MESH_KEYS, field)
    k = t.get("stiffness")
    if k is None:
        need = ("contact_ratio", "single_stiffness", "double_stiffness")
        if any(t.get(x) is None for x in need):
            raise ModelError(
                f"`{field}`: give `stiffness`, or `contact_ratio`, `single_stiffness` and "
                "`double_stiffness` (rectangular wave)"
            )
        k = rectangular_wave_coefficients(
            float(t["contact_ratio"]),
            float(t["single_stiffness"]),
            float(t["double_stiffness"]),
            int(t.get("stiffness_harmonics", 10)),
        )
    coeffs = {int(j): complex(v) for j, v in k.items()} if isinstance(k, Mapping) else {0: k}
    if not np.real(coeffs.get(0, 0)) > 0:
        raise ModelError(f"`{field}.stiffness` must have a positive mean [N/m], got {k!r}")
    damping = float(t.get("damping", 0.0))
    if not np.isfinite(damping) or damping < 0:
        raise ModelError(f"`{field}.damping` must be >= 0 [N s/m], got {damping!r}")
    te = t.get("transmission_error")
    te = None if not te else {int(j): complex(v) for j, v in te.items()}
    return MeshFamily({j: complex(v) for j, v in coeffs.items()}, damping, te)


def planet_data(
    planet: Mapping[str, Any] | None,
    bearing: Mapping[str, Any] | None,
    pin_errors: Sequence[Sequence[float]] | None,
    n_planets: int,
    pitch_diameter: float,
) -> PlanetData:
    """The planets' mass and inertia (``mass`` + ``inertia``, or ``width`` with the pitch
    diameter or ``outer_diameter``, ``inner_diameter`` and ``density`` or ``material``), their
    bearing (``stiffness``, ``damping`` on ``components`` of the planet's radial, tangential
    and axial axes) and pin errors."""
    p = _keys(planet, _PLANET_KEYS, "planet")
    if p.get("mass") is not None or p.get("inertia") is not None:
        if p.get("mass") is None or p.get("inertia") is None:
            raise ModelError("`planet`: give `mass` and `inertia` together")
        mass, inertia = float(p["mass"]), np.asarray(p["inertia"], dtype=float)
        J = np.diag(inertia) if inertia.shape == (3,) else inertia
        if (
            J.shape != (3, 3)
            or not np.isclose(J[0, 0], J[1, 1], rtol=1e-9)
            or np.any(np.abs(J - np.diag(np.diag(J))) > 1e-12 * np.abs(J).max())
        ):
            raise ModelError(
                "`planet.inertia`: a planet is axisymmetric: give (J_d, J_d, J_p) about its "
                f"radial, tangential and axial axes, got {p['inertia']!r}"
            )
    elif p.get("width") is not None:
        rho = material_constants(p.get("material"), {"density": p.get("density")}, "planet")
        node = disk(
            p.get("outer_diameter") or pitch_diameter,
            p["width"],
            float(rho["density"]),
            float(p.get("inner_diameter") or 0.0),
        )
        mass, inertia = node.mass, np.diag(node.inertia)
    else:
        raise ModelError("`planet`: give `mass` and `inertia`, or `width` (and a density)")
    b = _keys(bearing, _BEARING_KEYS, "planet_bearing")
    if b.get("stiffness") is None:
        raise ModelError("`planet_bearing.stiffness` is required")
    comps = b.get("components") or list(BEARING_COMPONENTS)
    K = expand_matrix(b["stiffness"], comps, "planet_bearing.stiffness")
    D = None if b.get("damping") is None else expand_matrix(b["damping"], comps, "damping")
    for i, c in enumerate(("ux", "uy", "uz", "phix", "phiy")):
        if K[i, i] <= 0:
            raise ModelError(
                f"`planet_bearing.stiffness`: the planets need a positive stiffness on {c} "
                f"(radial, tangential, axial, tilts in the planet's axes; give `components`)"
            )
    errors: tuple[np.ndarray, ...] = ()
    if pin_errors is not None:
        errors = tuple(np.asarray(e, dtype=float).ravel() for e in pin_errors)
        if len(errors) != n_planets or any(e.size not in (2, 3) for e in errors):
            raise ModelError(
                f"`pin_errors` needs one (radial, tangential[, axial]) entry per planet "
                f"({n_planets}), got {pin_errors!r}"
            )
    return PlanetData(mass, inertia, K, D, errors)


@dataclass(frozen=True)
class LoadSharing:
    """The mean (static) mesh forces of a set's planets and how evenly they share the load.

    Attributes
    ----------
    sun, ring
        Mean force [N] along the line of action of each planet's sun and ring mesh.
    factor
        ``N max(F_sun) / sum(F_sun)``: 1 for equal sharing.
    """

    sun: np.ndarray
    ring: np.ndarray

    @property
    def factor(self) -> float:
        return float(self.sun.size * np.max(self.sun) / np.sum(self.sun))


class PlanetaryTable(ModelData):
    """The vocabulary of planetary sets (a part of :class:`~rheolin.mechanics.model.Model`)."""

    def load_sharing(self, speed: float) -> dict[str, LoadSharing]:
        """Every set's static mesh forces at input ``speed`` [rad/s], from the static
        equilibrium (:meth:`operating_point`) under the static loads: torques, pin errors,
        the planets' orbit, gravity's mean. With the set's bodies in the carrier frame it is
        exact for supports that are isotropic about the axis; with them inertial the central
        members' translations are averaged out.
        """
        a = self.assemble(speed)  # type: ignore[attr-defined]
        u = self.operating_point(speed).displacement
        out = {}
        for name, s in self.planetary.items():
            forces = {}
            for kind, fam in (("sun", s.sun_mesh), ("ring", s.ring_mesh)):
                f = []
                for n in range(len(s.planets)):
                    term, w, _ = a.meshes[f"{name}.{kind}{n}"]
                    g = np.real(w.get(0, 0 * term.dofs)) if isinstance(w, dict) else w
                    f.append(float(np.real(fam.stiffness.get(0, 0))) * float(g @ u[term.dofs]))
                forces[kind] = np.array(f)
            out[name] = LoadSharing(forces["sun"], forces["ring"])
        return out

    @recorded
    def add_planetary(
        self,
        name: str,
        sun_body: str,
        sun_node: int,
        ring_body: str,
        ring_node: int,
        carrier_body: str,
        carrier_node: int,
        sun_teeth: int,
        planet_teeth: int,
        ring_teeth: int,
        module: float,
        planet: Mapping[str, Any],
        planet_bearing: Mapping[str, Any],
        sun_mesh: Mapping[str, Any],
        ring_mesh: Mapping[str, Any],
        planets: int | None = None,
        planet_angles: Sequence[float] | None = None,
        pressure_angle: float = float(np.radians(20.0)),
        helix_angle: float = 0.0,
        carrier_radius: float | None = None,
        angle_reference: Sequence[float] | None = None,
        side: int = 1,
        ring_phase: float = 0.0,
        pin_errors: Sequence[Sequence[float]] | None = None,
        frame: str = "carrier",
    ) -> None:
        """A planetary set on the sun, ring and carrier nodes, with ``planets`` equally spaced
        planets or planets at ``planet_angles`` [rad] (from ``angle_reference``, default the
        unbalance reference, right-handed about the carrier's axis), in the plane of the sun
        node; docs/planetary.md.

        ``module`` (normal), ``pressure_angle`` (normal), ``helix_angle`` (the sun's; planets
        have the other hand) and the tooth counts give the geometry; ``carrier_radius``
        defaults to the sun-planet centre distance. ``planet``: ``mass`` + ``inertia`` (about
        the radial, tangential and axial axes) or ``width`` (+ ``outer_diameter``, default
        the pitch diameter, ``inner_diameter``, ``density`` or ``material``).
        ``planet_bearing``: ``stiffness``/``damping`` on ``components`` of the planet's
        motion relative to its pin in the planet's radial (``ux``), tangential (``uy``) and
        axial (``uz``) axes; no stiffness about the axis. ``sun_mesh``, ``ring_mesh``: as
        :meth:`add_gear_mesh`'s stiffness keys, ``damping``, ``transmission_error`` (planet
        0's mesh; the others follow with their mesh phases). ``side`` +1: the sun pushes the
        planets forward (in its sense of rotation relative to the carrier). ``ring_phase``:
        the ring mesh's phase after the sun mesh of one planet [rad of the mesh cycle].
        ``pin_errors``: per planet, the pin's (radial, tangential[, axial]) position error [m].
        ``frame``: ``"carrier"`` writes the sun, ring and carrier bodies in the carrier's
        axes, ``"inertial"`` leaves them in global axes.
        """
        self.new_item(name, self.planetary)
        members = (
            ("sun", sun_body, sun_node),
            ("ring", ring_body, ring_node),
            ("carrier", carrier_body, carrier_node),
        )
        refs = {k: (b, self.node(self.body(b, f"{k}_body"), i)) for k, b, i in members}
        if len({sun_body, ring_body, carrier_body}) != 3:
            raise ModelError("`sun_body`, `ring_body` and `carrier_body` must be three bodies")
        nodes = [self.bodies[b].positions[i] for b, i in refs.values()]
        e = check_members([self.bodies[b].axis for b, _ in refs.values()], nodes)
        if (planets is None) == (planet_angles is None):
            raise ModelError("give `planets` (equally spaced) or `planet_angles`, one of them")
        angles = (
            equal_spacing(planets)
            if planets is not None
            else tuple(float(x) for x in np.asarray(planet_angles, dtype=float).ravel())
        )
        geo = PlanetaryGeometry(
            sun_teeth, planet_teeth, ring_teeth, angles, module, pressure_angle, helix_angle,
            carrier_radius or 0.0,
        )  # fmt: skip
        if frame not in FRAMES:
            raise ModelError(f"`frame` must be one of {list(FRAMES)}, got {frame!r}")
        if side not in (1, -1):
            raise ModelError(f"`side` must be +1 or -1, got {side!r}")
        ref = unbalance_reference(e, angle_reference or self.unbalance_reference)
        pitch = geo.transverse_module * geo.planet_teeth
        pdata = planet_data(planet, planet_bearing, pin_errors, geo.planets, pitch)
        names = tuple(planet_name(name, n) for n in range(geo.planets))
        for planet_body in names:
            self.new_body(planet_body, "name")
        record = PlanetarySet(
            name, geo, refs["sun"], refs["ring"], refs["carrier"], names, pdata,
            mesh_family(sun_mesh, "sun_mesh"), mesh_family(ring_mesh, "ring_mesh"), ref,
            int(side), float(ring_phase), frame,
        )  # fmt: skip
        centre = self.bodies[sun_body].positions[sun_node]
        contacts = geo.contacts(e, ref, centre, centre, centre)
        J = pdata.inertia if pdata.inertia.shape == (3, 3) else np.diag(pdata.inertia)
        for planet_body, c in zip(names, contacts, strict=True):
            body = Body(planet_body, "planet", e, c.position.reshape(1, 3), None, {"set": name})
            T = np.column_stack([c.radial, c.tangential, e])  # the planet's axes
            body.disks[0] = RigidNode(pdata.mass, T @ J @ T.T)
            self.bodies[planet_body] = body
        self.planetary[name] = record
