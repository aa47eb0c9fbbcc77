"""``rheolin.Model``: shafts, disks, bearings, gear meshes and loads -> a periodic system.

The names of the methods and arguments are those of the model file, one to one.

Examples
--------
A rigid rotor on an anisotropic bearing with a static unbalance, turning at 100 rad/s:

>>> import numpy as np, rheolin as rl
>>> m = Model()
>>> m.add_rigid_body("rotor", position=(0, 0, 0), mass=10.0, inertia=(0.1, 0.1, 0.2))
>>> m.add_disk("rotor", 0, unbalance=1e-4)
>>> m.add_bearing("b1", "rotor", 0, stiffness=[1e6, 2e6, 1e6, 1e4, 1e4, 1e4],
...               damping=[100.0, 100.0, 100.0, 1.0, 1.0, 0.0], components=None)
>>> a = m.assemble(speed=100.0)
>>> a.omega, a.plan.spin["rotor"], a.system.load_harmonics
(100.0, 1, [-1, 1])
>>> a.dof_labels[0]
('rotor', 0, 'ux')
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ModelError
from .assembly import Assembled
from .condensed import condensed_body
from .gears import mesh_record
from .items import Body, positive, recorded
from .joints import link_components
from .loads import gravity_vector, moment_at_node
from .planetary_model import PlanetaryTable
from .preload import preloaded_template
from .rigid import disk_node, given_node
from .rotation import unit_axis
from .sections import Section
from .shaft import layer_elements, shaft_layers, shaft_materials, shaft_nodes, tube_layers
from .speeds import GearPair, SpeedPlan
from .supports import SupportTable
from .template import SpeedTemplate, assemble_model, model_speed_plan

__all__ = ["Assembled", "Model"]


class Model(PlanetaryTable, SupportTable):
    """A transmission: bodies (shafts, rigid bodies), disks, joints, gear meshes and loads.

    Parameters
    ----------
    input_body
        Body whose speed is the ``speed`` given to :meth:`assemble`; default: the first body.
    unbalance_reference
        The global direction that is angle 0 of every unbalance (projected onto each disk's
        plane; :func:`~rheolin.mechanics.rigid.unbalance_reference`); default x (y for bodies
        turning about x).
    """

    def __init__(
        self, input_body: str | None = None, unbalance_reference: Sequence[float] | None = None
    ) -> None:
        super().__init__(input_body, unbalance_reference)

    @classmethod
    def from_ross(cls, rotor: Any) -> Model:
        """A model from a ROSS rotor: a ``ross.Rotor``, a file it saved (``.toml``/``.json``)
        or that file read into a dict; see :mod:`rheolin.io.ross` (ROSS is not needed for
        files)."""
        from ..io.ross import model_from_ross

        return model_from_ross(rotor)

    def to_toml(self, path: str | Path | None = None) -> str:
        """The model file (docs/model-format.md) of this model, SI units; written atomically
        to ``path`` when given. Loading it gives identical matrices (:mod:`rheolin.io.writer`).
        """
        from ..io.writer import model_to_toml

        return model_to_toml(self, path)

    # ------------------------------------------------------------------ bodies
    @recorded
    def add_shaft(
        self,
        name: str,
        positions: Sequence[float],
        outer_diameter: float | Sequence[float] | None = None,
        inner_diameter: float | Sequence[float] = 0.0,
        elastic_modulus: float | Sequence[float] | None = None,
        poisson_ratio: float | Sequence[float] | None = None,
        density: float | Sequence[float] | None = None,
        material_damping: float = 0.0,
        axis: Sequence[float] = (0.0, 0.0, 1.0),
        origin: Sequence[float] = (0.0, 0.0, 0.0),
        section: Section | None = None,
        speed_ratio: Fraction | int | None = None,
        shear_modulus: float | Sequence[float] | None = None,
        outer_diameter_right: float | Sequence[float] | None = None,
        inner_diameter_right: float | Sequence[float] | None = None,
        material: str | None = None,
    ) -> None:
        """A flexible shaft of Timoshenko elements with nodes along its spin axis.

        Parameters
        ----------
        name
            Body name.
        positions
            Axial node coordinates [m] from ``origin`` along ``axis``, strictly increasing.
        outer_diameter, inner_diameter
            Circular (tube) section, per shaft or per element [m] (at the left node of each
            element when the element is conical).
        outer_diameter_right, inner_diameter_right
            Diameters at the right node of each element [m] (default: the left ones); where
            they differ the element is conical (:mod:`rheolin.mechanics.conical`).
        elastic_modulus, density
            Material [Pa], [kg/m^3], per shaft or per element.
        poisson_ratio, shear_modulus
            Give one of them (per shaft or per element): Poisson's ratio [-] or the shear
            modulus ``G`` [Pa] that textbooks and ROSS give.
        material
            A named material (``"steel"``, ...: :data:`~rheolin.mechanics.sections.MATERIALS`)
            for the constants not given. rheolin assumes no material: without one, give
            ``elastic_modulus``, ``density`` and ``poisson_ratio`` or ``shear_modulus``.
        material_damping
            Rotating material damping ``beta`` [s] (``D_B = beta K_B``).
        axis, origin
            Spin axis and a point on it.
        section
            A non-circular :class:`~rheolin.mechanics.sections.Section` (e.g. ``Iy != Iz``)
            for every element, instead of the diameters; body axes = global axes at ``t = 0``.
        speed_ratio
            Speed relative to the input speed for a body not connected by gears.

        Examples
        --------
        >>> m = Model()
        >>> m.add_shaft("s", [0.0, 0.25, 0.5], outer_diameter=0.03, shear_modulus=81e9,
        ...             material="steel")
        >>> m.bodies["s"].positions[:, 2]
        array([0.  , 0.25, 0.5 ])
        >>> round(m.bodies["s"].data["layers"][0][0].material.nu, 4)
        0.2963
        """
        self.new_body(name)
        z, e, pts = shaft_nodes(positions, axis, origin)
        materials = shaft_materials(
            z.size - 1, material, elastic_modulus, density, poisson_ratio, shear_modulus,
            material_damping, f"add_shaft({name!r})",
        )  # fmt: skip
        layers = shaft_layers(
            materials, section, outer_diameter, inner_diameter, outer_diameter_right,
            inner_diameter_right,
        )  # fmt: skip
        ratio = None if speed_ratio is None else Fraction(speed_ratio)
        sections = [lay[0].section for lay in layers]
        data = {
            "lengths": np.diff(z),
            "layers": layers,
            "sections": sections,
            "material": materials[0],
            "extra_layers": [],
        }
        self.bodies[name] = Body(name, "shaft", e, pts, ratio, data)

    @recorded
    def add_shaft_layer(
        self,
        shaft: str,
        elements: Sequence[int],
        outer_diameter: float | Sequence[float],
        inner_diameter: float | Sequence[float] = 0.0,
        elastic_modulus: float | None = None,
        poisson_ratio: float | None = None,
        density: float | None = None,
        shear_modulus: float | None = None,
        outer_diameter_right: float | Sequence[float] | None = None,
        inner_diameter_right: float | Sequence[float] | None = None,
        material: str | None = None,
    ) -> None:
        """A concentric layer (sleeve, hub) added to some elements of a shaft.

        The layer acts in parallel with the element's own section: its Timoshenko matrices,
        with its own material and shear parameter, are added to the element's. A layer of
        negligible ``elastic_modulus`` adds mass and rotary inertia only.

        >>> m = Model()
        >>> m.add_shaft("s", [0.0, 0.1, 0.2], outer_diameter=0.05, material="steel")
        >>> m.add_shaft_layer("s", [1], outer_diameter=0.08, inner_diameter=0.05,
        ...                   material="aluminium")
        >>> [len(x) for x in m.bodies["s"].data["layers"]]
        [1, 2]
        """
        b = self.body(shaft, "shaft")
        idx = layer_elements(b.kind, shaft, len(b.positions) - 1, elements)
        mats = shaft_materials(
            len(idx), material, elastic_modulus, density, poisson_ratio, shear_modulus,
            b.data["material"].damping_beta, f"add_shaft_layer({shaft!r})",
        )  # fmt: skip
        layers, diameters = tube_layers(
            mats, outer_diameter, inner_diameter, outer_diameter_right, inner_diameter_right
        )
        for i, layer in zip(idx, layers, strict=True):
            b.data["layers"][i].append(layer)
        b.data["extra_layers"].append(dict(elements=idx, **diameters, materials=mats))

    @recorded
    def add_rigid_body(
        self,
        name: str,
        position: Sequence[float],
        mass: float,
        inertia: Sequence[float] | np.ndarray,
        axis: Sequence[float] = (0.0, 0.0, 1.0),
        speed_ratio: Fraction | int | None = None,
    ) -> None:
        """A body made of one rigid node (e.g. a gear on its own bearings, a housing mass)."""
        self.new_body(name)
        e = unit_axis(axis, "axis")
        pts = np.asarray(position, float).reshape(1, 3)
        ratio = None if speed_ratio is None else Fraction(speed_ratio)
        rigid = given_node(mass, inertia)
        self.bodies[name] = Body(name, "rigid", e, pts, ratio, disks={0: rigid})

    @recorded
    def add_condensed_body(
        self,
        name: str,
        positions: Sequence[Sequence[float]] | np.ndarray | None = None,
        M: Any = None,
        K: Any = None,
        D: Any = None,
        G: Any = None,
        frame: Sequence[Sequence[float]] | np.ndarray | None = None,
        path: str | None = None,
        axis: Sequence[float] = (0.0, 0.0, 1.0),
        speed_ratio: Fraction | int | None = None,
        body: Any = None,
    ) -> None:
        """A body given by condensed matrices in body axes (e.g. from an FE reduction).

        ``body``: a :class:`rheolin.fe.CondensedFE` (Craig-Bampton, :func:`rheolin.fe.condense`)
        whose interface nodes become the body's nodes (``positions`` default to its reference
        points) and whose modes become extra DOFs; a ``.npz`` it saved works as ``path``.

        ``M``, ``K`` (and optional rotating damping ``D``, gyroscopic matrix per unit speed
        ``G``) are ``6 n x 6 n`` over the body's ``n`` nodes at ``positions`` (node-major,
        DOFs ``ux, uy, uz, phix, phiy, phiz``); ``frame`` holds the body axes as columns at
        ``t = 0``. Or give ``path``: a ``.npz`` with arrays ``M, K`` and optionally
        ``D, G, frame`` (read by :func:`~rheolin.mechanics.condensed.load_condensed`).

        >>> import numpy as np
        >>> m = Model()
        >>> m.add_condensed_body("housing", [[0, 0, 0]], M=10 * np.eye(6), K=np.zeros((6, 6)))
        >>> m.bodies["housing"].kind
        'condensed'
        """
        self.new_body(name)
        pts, cb = condensed_body(positions, M, K, D, G, frame, path, body)
        ratio = None if speed_ratio is None else Fraction(speed_ratio)
        e = unit_axis(axis, "axis")
        self.bodies[name] = Body(name, "condensed", e, pts, ratio, {"condensed": cb})

    @recorded
    def add_disk(
        self,
        body: str,
        node: int,
        mass: float | None = None,
        inertia: Sequence[float] | np.ndarray | None = None,
        outer_diameter: float | None = None,
        width: float | None = None,
        density: float | None = None,
        inner_diameter: float = 0.0,
        unbalance: float = 0.0,
        unbalance_angle: float = 0.0,
        couple_unbalance: float = 0.0,
        couple_angle: float = 0.0,
        material: str | None = None,
        axial_offset: float = 0.0,
    ) -> None:
        """A rigid disk / gear blank at a body node, optionally with unbalance.

        Give either ``mass`` and ``inertia`` (about the centre of mass, body axes) or the
        geometry ``outer_diameter``, ``width``, ``inner_diameter`` and ``density`` (or a named
        ``material``, e.g. ``"steel"``: rheolin assumes none). With neither,
        the unbalance is added to the node's existing disk. ``unbalance`` [kg m] is static at
        ``unbalance_angle``; ``couple_unbalance`` [kg m^2] is dynamic at ``couple_angle``.
        ``axial_offset`` [m] puts the disk's centre of mass that far from the node along the
        body's spin axis (a disk overhung on its hub, a gear beside its bearing seat): the
        node carries the disk's mass and inertia with their lever arm, coupling translation and
        tilt exactly (no extra node, no stiff link).
        """
        b = self.body(body, "body")
        node = self.node(b, node)
        b.disks[node] = disk_node(
            b.disks.get(node), b.axis, self.unbalance_reference, body, node, mass, inertia,
            outer_diameter, width, density, inner_diameter, unbalance, unbalance_angle,
            couple_unbalance, couple_angle, material, axial_offset,
        )  # fmt: skip

    # ------------------------------------------------------------------ joints and loads
    @recorded
    def add_gear_mesh(
        self,
        name: str,
        pinion_body: str,
        pinion_node: int,
        gear_body: str,
        gear_node: int,
        pinion_teeth: int,
        gear_teeth: int,
        module: float,
        pressure_angle: float = np.radians(20.0),
        helix_angle: float = 0.0,
        stiffness: float | dict[int, complex] | None = None,
        contact_ratio: float | None = None,
        single_stiffness: float | None = None,
        double_stiffness: float | None = None,
        stiffness_harmonics: int = 10,
        damping: float = 0.0,
        transmission_error: dict[int, complex] | None = None,
        side: int = 1,
        center_direction: Sequence[float] | None = None,
        load_law: str | None = None,
        face_width: float | None = None,
        load_forces: Sequence[float] | None = None,
        load_stiffness: Sequence[float] | None = None,
    ) -> None:
        """An external spur/helical mesh between parallel axes.

        ``module`` is the normal module [m], ``pressure_angle`` the normal pressure angle
        [rad]. Mesh stiffness: ``stiffness`` (mean [N/m] or ``{j: k_j}`` over mesh harmonics),
        or the rectangular wave of ``contact_ratio``, ``single_stiffness``,
        ``double_stiffness`` truncated at ``stiffness_harmonics``. ``transmission_error`` is
        ``{j: e_j}`` [m]: the static (unloaded) transmission error, entering as the load
        ``k(t) e(t)`` on the line of action; the mesh damping acts on the dynamic deflection
        rate only (Ozguven & Houser). ``side`` selects the flank (see ``gears.line_of_action``).

        Load-dependent stiffness (:class:`~rheolin.mechanics.rolling.MeshLoadLaw`): the mean
        stiffness becomes ``k(F)`` of the static mesh force, by ``load_law="iso6336"`` (with
        ``face_width`` [m]: ISO 6336-1's reduction below 100 N/mm) or ``"table"``
        (``load_stiffness`` [N/m] at ``load_forces`` [N]); the whole stiffness function is
        scaled by the operating (tangent) stiffness over its mean. The model is then solved
        about its operating point (:mod:`rheolin.mechanics.preload`).
        """
        self.new_item(name, self.meshes)
        for fld, bname, node in (
            ("pinion_body", pinion_body, pinion_node),
            ("gear_body", gear_body, gear_node),
        ):
            self.node(self.body(bname, fld), node)
        if pinion_body == gear_body:
            raise ModelError("`gear_body` must differ from `pinion_body`")
        pair = GearPair(pinion_body, gear_body, pinion_teeth, gear_teeth)
        mesh = mesh_record(
            module, pressure_angle, helix_angle, stiffness, contact_ratio, single_stiffness,
            double_stiffness, stiffness_harmonics, damping, transmission_error, side,
            center_direction, load_law, face_width, load_forces, load_stiffness,
        )  # fmt: skip
        self.meshes[name] = dict(pair=pair, pinion_node=pinion_node, gear_node=gear_node, **mesh)

    @recorded
    def add_force(
        self,
        name: str,
        body: str,
        node: int,
        force: Sequence[float] = (0.0, 0.0, 0.0),
        moment: Sequence[float] = (0.0, 0.0, 0.0),
        order: Fraction | int = 0,
        phase: float = 0.0,
        reference_body: str | None = None,
        offset: Sequence[float] | None = None,
    ) -> None:
        """``F cos(order * W_ref t + phase)`` at a node, fixed in direction (global axes).

        ``order`` is relative to the speed of ``reference_body`` (default: ``body``); 0 is a
        static force. ``offset`` [m]: the force acts at a point that far from the node, rigidly
        attached to it; the node carries it with the moment ``r x F`` added.
        """
        self.new_item(name, self.forces)
        self.node(self.body(body, "body"), node)
        ref = body if reference_body is None else reference_body
        self.body(ref, "reference_body")
        self.forces[name] = dict(
            body=body,
            node=node,
            force=[float(x) for x in force],
            moment=moment_at_node(force, moment, offset),
            order=Fraction(order),
            phase=float(phase),
            reference=ref,
        )

    @recorded
    def add_rigid_link(
        self,
        name: str,
        body: str,
        node: int,
        other_body: str,
        other_node: int,
        components: Sequence[str] | None = None,
    ) -> None:
        """An exact rigid connection: ``other_node`` follows ``node`` as if welded to it,
        ``u_b = u_a + phi_a x (p_b - p_a)``, ``phi_b = phi_a`` (``components``: only those of
        the other node's DOFs; None: all six). The constrained DOFs are eliminated from the
        equations (:mod:`rheolin.system.constraints`), not tied by a stiff spring: a short massless
        connecting piece, a keyed hub or a stiff coupling without ill-conditioning. Chains of
        links are resolved; a DOF constrained twice is refused.

        >>> m = Model()
        >>> m.add_rigid_body("a", (0, 0, 0), 1.0, (1.0, 1.0, 1.0))
        >>> m.add_rigid_body("b", (0, 0, 0.5), 1.0, (1.0, 1.0, 1.0))
        >>> m.add_rigid_link("weld", "a", 0, "b", 0)
        >>> m.assemble(1.0).system.constraint.pivots.size
        6
        """
        self.new_item(name, self.links)
        self.node(self.body(body, "body"), node)
        self.node(self.body(other_body, "other_body"), other_node)
        if (body, node) == (other_body, other_node):
            raise ModelError("`other_node`: a rigid link needs two different nodes")
        self.links[name] = dict(
            body=body, node=int(node), other_body=other_body, other_node=int(other_node),
            components=link_components(components),
        )  # fmt: skip

    @recorded
    def set_gravity(self, gravity: Sequence[float] = (0.0, -9.81, 0.0)) -> None:
        """Uniform gravity [m/s^2] in global axes (static load ``M g`` on every body)."""
        self.gravity = gravity_vector(gravity)

    # ------------------------------------------------------------------ assembly
    def speed_plan(self) -> SpeedPlan:
        """Exact speed ratios, ``w1 / speed`` and integer harmonics of the model."""
        return model_speed_plan(self)

    def assemble(self, speed: float) -> Assembled:
        """Assemble at input speed ``speed`` [rad/s] (> 0); see :class:`Assembled`. A
        :attr:`preloaded` model is assembled linearized about its operating point."""
        speed = positive(speed, "speed")
        if self.preloaded:
            return self.operating_point(speed).model.assemble(speed)
        return assemble_model(self, speed)

    def speed_template(self) -> Any:
        """The model assembled once for many speeds (:class:`SpeedTemplate`): its
        ``assemble(speed)`` only scales the speed-dependent coefficients. Make a new one after
        changing the model. A :attr:`preloaded` model whose static stiffness does not
        depend on the speed is linearized once; otherwise at each speed."""
        if self.preloaded:
            return preloaded_template(self)
        return SpeedTemplate(self)
