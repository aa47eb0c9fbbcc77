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

import functools
import inspect
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any, ParamSpec, TypeVar

import numpy as np

from ..errors import ModelError
from .assembly import Assembled
from .bearing_table import SpeedTable
from .condensed import CondensedBody, load_condensed
from .gears import rectangular_wave_coefficients
from .joints import COMPONENTS, expand_matrix, lever
from .rigid import RigidNode, disk, static_unbalance
from .rigid import couple_unbalance as _add_couple
from .rotation import unit_axis
from .sections import Section, element_materials, material_constants
from .shaft import ShaftLayer, circular_layer
from .speeds import GearPair, SpeedPlan
from .template import SpeedTemplate, assemble_model, model_speed_plan

__all__ = ["Assembled", "Model"]

_P = ParamSpec("_P")
_R = TypeVar("_R")


def _recorded(method: Callable[_P, _R]) -> Callable[_P, _R]:
    """Record a successful ``add_*`` call (its explicit arguments) in ``model.calls``: the
    model file is these calls one to one (:meth:`Model.to_toml`)."""
    sig = inspect.signature(method)

    @functools.wraps(method)
    def wrapper(*args: _P.args, **kwargs: _P.kwargs) -> _R:
        out = method(*args, **kwargs)
        bound = sig.bind(*args, **kwargs).arguments
        model = bound.pop("self")
        model.calls.append((method.__name__, dict(bound)))
        return out

    return wrapper


@dataclass
class _Body:
    name: str
    kind: str  # "shaft" | "rigid" | "condensed"
    axis: np.ndarray
    positions: np.ndarray  # (n_nodes, 3)
    speed_ratio: Fraction | None
    data: dict[str, Any] = field(default_factory=dict)
    disks: dict[int, RigidNode] = field(default_factory=dict)


def _shaft_constants(
    material: str | None,
    elastic_modulus: Any,
    density: Any,
    poisson_ratio: Any,
    shear_modulus: Any,
    where: str,
) -> tuple[Any, Any, Any]:
    """Elastic modulus, density and Poisson's ratio (not needed with a shear modulus): given,
    or from the named ``material``; refused when neither (rheolin assumes no material)."""
    need = {"elastic_modulus": elastic_modulus, "density": density}
    if shear_modulus is None:
        need["poisson_ratio"] = poisson_ratio
    c = material_constants(material, need, where)
    return c["elastic_modulus"], c["density"], c.get("poisson_ratio", poisson_ratio)


class Model:
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
        self.input_body = input_body
        self.unbalance_reference = (
            None if unbalance_reference is None else tuple(float(v) for v in unbalance_reference)
        )
        ref = np.asarray(self.unbalance_reference or (1.0, 0.0, 0.0), dtype=float)
        if ref.shape != (3,) or not np.all(np.isfinite(ref)) or not np.any(ref):
            raise ModelError(
                f"`unbalance_reference` must be a nonzero 3-vector, got {unbalance_reference!r}"
            )
        self.bodies: dict[str, _Body] = {}
        self.joints: dict[str, dict[str, Any]] = {}
        self.meshes: dict[str, dict[str, Any]] = {}
        self.forces: dict[str, dict[str, Any]] = {}
        self.links: dict[str, dict[str, Any]] = {}
        #: load-dependent joints and applied torques (operating point: mechanics.preload)
        self.rolling: dict[str, dict[str, Any]] = {}
        self.torques: dict[str, dict[str, Any]] = {}
        self.gravity: np.ndarray | None = None
        self._operating: dict[tuple[float, int], Any] = {}
        #: ``(method, arguments)`` of every ``add_*``/``set_gravity`` call, in order.
        self.calls: list[tuple[str, dict[str, Any]]] = []

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
    def _new_body(self, name: str, field_name: str = "name") -> None:
        if not isinstance(name, str) or not name:
            raise ModelError(f"`{field_name}` must be a non-empty string, got {name!r}")
        if name in self.bodies:
            raise ModelError(f"`{field_name}`: a body named {name!r} already exists")

    @_recorded
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
        self._new_body(name)
        z = np.asarray(positions, dtype=float).ravel()
        if z.size < 2 or np.any(np.diff(z) <= 0):
            raise ModelError("`positions` must hold >= 2 strictly increasing axial coordinates")
        e = unit_axis(axis, "axis")
        pts = np.asarray(origin, float) + np.outer(z, e)
        n_el = z.size - 1
        E, rho, nu = _shaft_constants(
            material, elastic_modulus, density, poisson_ratio, shear_modulus, f"add_shaft({name!r})"
        )
        materials = element_materials(n_el, E, rho, nu, shear_modulus, material_damping)
        if section is not None:
            if not isinstance(section, Section):
                raise ModelError("`section` must be a rheolin.mechanics.sections.Section")
            if outer_diameter_right is not None or inner_diameter_right is not None:
                raise ModelError("`outer_diameter_right`/`inner_diameter_right` need diameters")
            layers = [[ShaftLayer(mat, section=section)] for mat in materials]
        elif outer_diameter is None:
            raise ModelError("give `outer_diameter` (circular shaft) or `section`")
        else:
            do = _per_element(outer_diameter, n_el, "outer_diameter")
            di = _per_element(inner_diameter, n_el, "inner_diameter")
            dor = (
                do
                if outer_diameter_right is None
                else _per_element(outer_diameter_right, n_el, "outer_diameter_right")
            )
            dir_ = (
                di
                if inner_diameter_right is None
                else _per_element(inner_diameter_right, n_el, "inner_diameter_right")
            )
            layers = [
                [circular_layer(mat, a, b, c, d)]
                for mat, a, b, c, d in zip(materials, do, di, dor, dir_, strict=True)
            ]
        ratio = None if speed_ratio is None else Fraction(speed_ratio)
        sections = [lay[0].section for lay in layers]
        data = {
            "lengths": np.diff(z),
            "layers": layers,
            "sections": sections,
            "material": materials[0],
            "extra_layers": [],
        }
        self.bodies[name] = _Body(name, "shaft", e, pts, ratio, data)

    @_recorded
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
        b = self._body(shaft, "shaft")
        if b.kind != "shaft":
            raise ModelError(f"`shaft`: body {shaft!r} is a {b.kind} body, not a shaft")
        n_el = len(b.positions) - 1
        idx = [int(i) for i in np.atleast_1d(np.asarray(elements)).ravel()]
        if not idx or any(not 0 <= i < n_el for i in idx):
            raise ModelError(f"`elements` must be element indices in [0, {n_el}), got {elements!r}")
        k = len(idx)
        E, rho, nu = _shaft_constants(
            material,
            elastic_modulus,
            density,
            poisson_ratio,
            shear_modulus,
            f"add_shaft_layer({shaft!r})",
        )
        mats = element_materials(k, E, rho, nu, shear_modulus, b.data["material"].damping_beta)
        do = _per_element(outer_diameter, k, "outer_diameter")
        di = _per_element(inner_diameter, k, "inner_diameter")
        dor = (
            do
            if outer_diameter_right is None
            else _per_element(outer_diameter_right, k, "outer_diameter_right")
        )
        dir_ = (
            di
            if inner_diameter_right is None
            else _per_element(inner_diameter_right, k, "inner_diameter_right")
        )
        for j, i in enumerate(idx):
            b.data["layers"][i].append(circular_layer(mats[j], do[j], di[j], dor[j], dir_[j]))
        b.data["extra_layers"].append(
            dict(
                elements=idx,
                outer_diameter=do,
                inner_diameter=di,
                outer_diameter_right=dor,
                inner_diameter_right=dir_,
                materials=mats,
            )
        )

    @_recorded
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
        self._new_body(name)
        e = unit_axis(axis, "axis")
        pts = np.asarray(position, float).reshape(1, 3)
        ratio = None if speed_ratio is None else Fraction(speed_ratio)
        self.bodies[name] = _Body(name, "rigid", e, pts, ratio)
        self.bodies[name].disks[0] = RigidNode(mass, np.asarray(inertia, dtype=float))

    @_recorded
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
        self._new_body(name)
        if body is not None:
            if path is not None or M is not None:
                raise ModelError("give one of `body`, `path` or the matrices `M`, `K`")
            M, K, D, G = body.M, body.K, body.D, body.G
        if positions is None:
            if body is not None:
                positions = body.positions
            elif path is not None:
                with np.load(path) as z:
                    if "positions" not in z.files:
                        raise ModelError("`positions`: required (the file has no `positions`)")
                    positions = z["positions"]
            else:
                raise ModelError("`positions`: give one 3-vector per node")
        pts = np.asarray(positions, dtype=float).reshape(-1, 3)
        nodes = list(range(len(pts)))  # body-local; the assembly maps them to global nodes
        axes = None if frame is None else np.asarray(frame, dtype=float)
        if body is not None:
            cb = CondensedBody(
                M=M, K=K, nodes=nodes, D=D, G=G, frame=axes, n_modes=body.n_modes, C=body.C
            )
        elif path is not None:
            if M is not None or K is not None:
                raise ModelError("give either `path` or the matrices `M`, `K`, not both")
            cb = load_condensed(path, nodes=nodes, frame=axes)
        else:
            if M is None or K is None:
                raise ModelError("a condensed body needs `M` and `K` (or a `path`)")
            cb = CondensedBody(M=M, K=K, nodes=nodes, D=D, G=G, frame=axes)
        ratio = None if speed_ratio is None else Fraction(speed_ratio)
        e = unit_axis(axis, "axis")
        self.bodies[name] = _Body(name, "condensed", e, pts, ratio, {"condensed": cb})

    @_recorded
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
        b = self._body(body, "body")
        node = self._node(b, node)
        e = b.axis
        if mass is not None or inertia is not None:
            if mass is None or inertia is None:
                raise ModelError("`mass` and `inertia` must be given together")
            rn = RigidNode(mass, np.asarray(inertia, dtype=float))
        elif outer_diameter is not None:
            if width is None:
                raise ModelError("`width` is required with `outer_diameter`")
            rho = material_constants(material, {"density": density}, f"add_disk({body!r})")
            rn = disk(outer_diameter, width, float(rho["density"]), inner_diameter, axis=e)
        elif node in b.disks:
            rn = b.disks[node]
        else:
            raise ModelError("give `mass` and `inertia`, or `outer_diameter` and `width`")
        if unbalance:
            rn = static_unbalance(rn, unbalance, unbalance_angle, axis=e,
                                  reference=self.unbalance_reference)  # fmt: skip
        if couple_unbalance:
            rn = _add_couple(rn, couple_unbalance, couple_angle, axis=e,
                             reference=self.unbalance_reference)  # fmt: skip
        if node in b.disks and (mass is not None or outer_diameter is not None):
            raise ModelError(f"`node`: node {node} of body {body!r} already has a disk")
        if axial_offset:
            if not np.isfinite(axial_offset):
                raise ModelError(f"`axial_offset` must be finite, got {axial_offset!r}")
            if rn.mass <= 0.0:
                raise ModelError("`axial_offset` needs a disk with mass")
            rn = RigidNode(rn.mass, rn.inertia, rn.com + float(axial_offset) * np.asarray(e))
        b.disks[node] = rn

    # ------------------------------------------------------------------ joints and loads
    @_recorded
    def add_bearing(
        self,
        name: str,
        body: str,
        node: int,
        stiffness: Any = 0.0,
        damping: Any = 0.0,
        components: Sequence[str] | None = ("ux", "uy"),
        other_body: str | None = None,
        other_node: int | None = None,
        frame: str | None = None,
        mass: Any = 0.0,
        speeds: Sequence[float] | None = None,
        interpolation: str = "cubic",
        extrapolate: bool = False,
        offset: Sequence[float] | None = None,
        other_offset: Sequence[float] | None = None,
        preload: Sequence[float] | None = None,
    ) -> None:
        """A bearing, seal or coupling from a node to ground (default) or to another body's node.

        ``stiffness`` / ``damping`` / ``mass`` (added mass) act on the relative displacement,
        over ``components`` (names from ``COMPONENTS``; None means all six): a scalar, a
        vector (diagonal) or a matrix (cross-coupling, anisotropy). ``frame=None``: constant
        in the inertial frame; ``frame="<body>"``: defined in that body's rotating axes.

        Speed-dependent coefficients (journal bearings, seals): give ``speeds`` [rad/s of the
        bearing's ``body``] and one coefficient per speed in ``stiffness``, ``damping`` and
        ``mass`` (a scalar is the same at every speed); they are interpolated by
        ``interpolation`` (see :class:`~rheolin.mechanics.bearing_table.SpeedTable`) and
        evaluated at the operating speed by every solver, Campbell diagram and stability map.

        ``offset`` [m] (global axes) puts the bearing at a point that far from the node, rigidly
        attached to it (a bearing seat beside a shaft node, a housing foot off its node): the
        coefficients act on the point's motion ``u + phi x r``, which couples the node's
        translations and tilts exactly; ``other_offset`` likewise on the other body's side.
        Inertial-frame joints only (``frame=None``).

        ``preload`` [N, N m] (global axes): the force (3) or force and moment (6) the joint
        exerts on its support at zero relative displacement, a preloaded spring: it acts as
        ``preload + K delta``; the static load ``-preload`` on the node (``+preload`` on the
        other node) and the reported bearing force include it. A linearized load-dependent
        joint is such a spring (:mod:`rheolin.mechanics.preload`). Constant joints only.

        >>> m = Model()
        >>> m.add_shaft("s", [0.0, 0.5], outer_diameter=0.05, material="steel")
        >>> m.add_bearing("b", "s", 0, stiffness=[[[1e7, 2e6], [-2e6, 1e7]], [[2e7, 4e6],
        ...               [-4e6, 2e7]]], damping=[1e3, 2e3], speeds=[100.0, 300.0],
        ...               interpolation="linear")
        >>> float(m.bearing_coefficients("b", 200.0)[0][0, 1])
        3000000.0
        """
        self._joint_nodes(name, body, node, other_body, other_node)
        if frame is not None:
            self._body(frame, "frame")
        if frame is not None and (offset is not None or other_offset is not None):
            raise ModelError("`offset`: only for joints in the inertial frame (frame=None)")
        if other_offset is not None and other_body is None:
            raise ModelError("`other_offset` needs `other_body` (a joint to ground has one side)")
        lever(offset)  # checked: a finite 3-vector
        lever(other_offset)
        pre = None
        if preload is not None:
            pre = np.asarray(preload, dtype=float).ravel()
            if pre.size not in (3, 6) or not np.all(np.isfinite(pre)):
                raise ModelError(
                    "`preload` must be 3 (force) or 6 (force, moment) finite numbers, "
                    f"got {preload!r}"
                )
            if frame is not None or speeds is not None:
                raise ModelError("`preload`: only for constant joints in the inertial frame")
            pre = np.concatenate([pre, np.zeros(6 - pre.size)])
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
        self.joints[name] = dict(
            body=body,
            node=node,
            other=(other_body, other_node),
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

    @_recorded
    def add_rolling_bearing(
        self,
        name: str,
        body: str,
        node: int,
        law: str = "elements",
        kind: str = "ball",
        stiffness: float = 0.0,
        elements: int = 0,
        clearance: float = 0.0,
        angle: float = 0.0,
        deflection: Sequence[float] | None = None,
        force: Sequence[float] | None = None,
        damping: float = 0.0,
        other_body: str | None = None,
        other_node: int | None = None,
    ) -> None:
        """A rolling-element bearing whose radial stiffness depends on its load.

        ``law``: ``"elements"`` (``elements`` rolling elements, each with the Hertz law
        ``Q = stiffness <delta - clearance>^n``, ``n`` 3/2 for ``kind="ball"``, 10/9 for
        ``"roller"``; ``angle`` places element 0), ``"radial"`` (one lumped law
        ``|F| = stiffness <|d| - clearance>^n`` for the bearing) or ``"table"`` (radial
        ``force`` [N] against ``deflection`` [m]); see :mod:`rheolin.mechanics.rolling`.
        The force acts in the bearing plane (normal to the body's axis) on the node's motion
        relative to ground or to ``other_node``; ``damping`` [N s/m] is a constant radial
        damping. The model is then solved about its operating point (static equilibrium
        under gravity, static forces and torques; :mod:`~rheolin.mechanics.preload`), where this
        bearing becomes a linear joint with its tangent stiffness.

        >>> m = Model()
        >>> m.add_shaft("s", [0.0, 0.2], outer_diameter=0.04, material="steel")
        >>> m.add_rolling_bearing("a", "s", 0, kind="ball", stiffness=8e9, elements=9)
        >>> sorted(m.rolling)
        ['a']
        """
        from .rolling import RollingLaw

        self._joint_nodes(name, body, node, other_body, other_node)
        rolling_law = RollingLaw(
            law=law,
            kind=kind,
            stiffness=float(stiffness),
            elements=elements,
            clearance=float(clearance),
            angle=float(angle),
            deflection=None if deflection is None else np.asarray(deflection, float),
            force_table=None if force is None else np.asarray(force, float),
        )
        if not (np.isfinite(damping) and damping >= 0):
            raise ModelError(f"`damping` must be >= 0 [N s/m], got {damping!r}")
        self.rolling[name] = dict(
            body=body,
            node=int(node),
            other=(other_body, other_node),
            law=rolling_law,
            damping=float(damping),
        )

    @_recorded
    def add_torque(self, name: str, body: str, node: int, torque: float | str = "reaction") -> None:
        """A static torque [N m] about the body's axis at a node (positive: right-handed
        about the axis): the input torque, or the output load. ``torque="reaction"``: the
        torque that balances all the others on the free rotation of the drive train (the
        output load of a gearbox driven by a given input torque). The model is then solved
        about its operating point (:mod:`rheolin.mechanics.preload`).

        >>> m = Model()
        >>> m.add_rigid_body("r", (0, 0, 0), 1.0, (1e-3, 1e-3, 2e-3))
        >>> m.add_torque("input", "r", 0, 12.5)
        >>> m.torques["input"]["torque"]
        12.5
        """
        self._new_item(name, self.torques)
        self._node(self._body(body, "body"), node)
        if isinstance(torque, str):
            if torque != "reaction":
                raise ModelError(f"`torque` must be a number [N m] or 'reaction', got {torque!r}")
        else:
            try:
                torque = float(torque)
            except (TypeError, ValueError):
                raise ModelError(
                    f"`torque` must be a number [N m] or 'reaction', got {torque!r}"
                ) from None
            if not np.isfinite(torque):
                raise ModelError(f"`torque` must be finite, got {torque!r}")
        self.torques[name] = dict(body=body, node=int(node), torque=torque)

    @property
    def preloaded(self) -> bool:
        """True when the model declares torques or load-dependent joints: it is solved about
        its operating point (:meth:`operating_point`)."""
        return bool(self.rolling or self.torques) or any(
            g.get("load_law") is not None for g in self.meshes.values()
        )

    def operating_point(self, speed: float) -> Any:
        """The static equilibrium under the model's static loads and torques at input
        ``speed`` [rad/s], and the model linearized there
        (:class:`rheolin.mechanics.preload.OperatingPoint`); cached per speed."""
        from .preload.equilibrium import operating_point

        key = (_positive(speed, "speed"), len(self.calls))  # a changed model: computed anew
        if key not in self._operating:
            if len(self._operating) > 64:
                self._operating.clear()
            self._operating[key] = operating_point(self, key[0])
        return self._operating[key]

    def _new_joint(self, name: str) -> None:
        self._new_item(name, self.joints)
        self._new_item(name, self.rolling)

    def _joint_nodes(
        self, name: str, body: str, node: int, other_body: str | None, other_node: int | None
    ) -> None:
        """Check a new joint's name and nodes (``other_*``: the other side, or ground)."""
        self._new_joint(name)
        self._node(self._body(body, "body"), node)
        if (other_body is None) != (other_node is None):
            raise ModelError("`other_body` and `other_node` must be given together")
        if other_body is not None:
            self._node(self._body(other_body, "other_body"), other_node)

    def bearing_coefficients(
        self, name: str, speed: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(K, D, M)`` (6x6) of joint ``name`` at its body's ``speed`` [rad/s]."""
        if name not in self.joints:
            raise ModelError(f"`name`: no bearing {name!r}; bearings: {list(self.joints)}")
        j = self.joints[name]
        if j["table"] is not None:
            return j["table"].at(speed)
        return j["K"], j["D"], j["M"]

    @_recorded
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
        self._new_item(name, self.meshes)
        for fld, bname, node in (
            ("pinion_body", pinion_body, pinion_node),
            ("gear_body", gear_body, gear_node),
        ):
            self._node(self._body(bname, fld), node)
        if pinion_body == gear_body:
            raise ModelError("`gear_body` must differ from `pinion_body`")
        pair = GearPair(pinion_body, gear_body, pinion_teeth, gear_teeth)
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
        _positive(module, "module")
        mesh_law = None
        if load_law is not None:
            from .rolling import MeshLoadLaw

            mesh_law = MeshLoadLaw(
                law=load_law,
                face_width=float(face_width or 0.0),
                forces=None if load_forces is None else np.asarray(load_forces, float),
                stiffness=None if load_stiffness is None else np.asarray(load_stiffness, float),
            )
        self.meshes[name] = dict(
            pair=pair,
            pinion_node=pinion_node,
            gear_node=gear_node,
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

    @_recorded
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
        self._new_item(name, self.forces)
        self._node(self._body(body, "body"), node)
        ref = body if reference_body is None else reference_body
        self._body(ref, "reference_body")
        T = lever(offset)
        if T is not None:  # F at r: the node's load is T^T (F, M) = (F, M + r x F)
            moment = list(
                T.T @ np.concatenate([np.asarray(force, float), np.asarray(moment, float)])
            )[3:]
        self.forces[name] = dict(
            body=body,
            node=node,
            force=force,
            moment=moment,
            order=Fraction(order),
            phase=float(phase),
            reference=ref,
        )

    @_recorded
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
        self._new_item(name, self.links)
        self._node(self._body(body, "body"), node)
        self._node(self._body(other_body, "other_body"), other_node)
        if (body, node) == (other_body, other_node):
            raise ModelError("`other_node`: a rigid link needs two different nodes")
        comps = list(COMPONENTS) if components is None else list(components)
        bad = [c for c in comps if c not in COMPONENTS]
        if bad or not comps or len(set(comps)) != len(comps):
            raise ModelError(
                f"`components` must be distinct names from {list(COMPONENTS)}, got {components!r}"
            )
        self.links[name] = dict(
            body=body, node=int(node), other_body=other_body, other_node=int(other_node),
            components=comps,
        )  # fmt: skip

    @_recorded
    def set_gravity(self, gravity: Sequence[float] = (0.0, -9.81, 0.0)) -> None:
        """Uniform gravity [m/s^2] in global axes (static load ``M g`` on every body)."""
        g = np.asarray(gravity, dtype=float).ravel()
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise ModelError(f"`gravity` must be a finite 3-vector [m/s^2], got {gravity!r}")
        self.gravity = g

    # ------------------------------------------------------------------ assembly
    def speed_plan(self) -> SpeedPlan:
        """Exact speed ratios, ``w1 / speed`` and integer harmonics of the model."""
        return model_speed_plan(self)

    def assemble(self, speed: float) -> Assembled:
        """Assemble at input speed ``speed`` [rad/s] (> 0); see :class:`Assembled`. A
        :attr:`preloaded` model is assembled linearized about its operating point."""
        speed = _positive(speed, "speed")
        if self.preloaded:
            return self.operating_point(speed).model.assemble(speed)
        return assemble_model(self, speed)

    def speed_template(self) -> Any:
        """The model assembled once for many speeds (:class:`SpeedTemplate`): its
        ``assemble(speed)`` only scales the speed-dependent coefficients. Make a new one after
        changing the model. A :attr:`preloaded` model whose static stiffness does not
        depend on the speed is linearized once; otherwise at each speed."""
        if self.preloaded:
            from .preload.equilibrium import preloaded_template

            return preloaded_template(self)
        return SpeedTemplate(self)

    def _body(self, name: str, field_name: str) -> _Body:
        if name not in self.bodies:
            raise ModelError(f"`{field_name}`: no body named {name!r}; bodies: {list(self.bodies)}")
        return self.bodies[name]

    @staticmethod
    def _node(b: _Body, node: Any) -> int:
        if (
            isinstance(node, bool)
            or not isinstance(node, int | np.integer)
            or not (0 <= node < len(b.positions))
        ):
            raise ModelError(
                f"`node` must be an integer in [0, {len(b.positions)}) for body "
                f"{b.name!r}, got {node!r}"
            )
        return int(node)

    @staticmethod
    def _new_item(name: str, table: dict[str, Any]) -> None:
        if not isinstance(name, str) or not name:
            raise ModelError(f"`name` must be a non-empty string, got {name!r}")
        if name in table:
            raise ModelError(f"`name`: {name!r} is already used")


def _positive(x: Any, name: str) -> float:
    try:
        v = float(x)
    except (TypeError, ValueError):
        raise ModelError(f"`{name}` must be a positive number, got {x!r}") from None
    if not np.isfinite(v) or v <= 0:
        raise ModelError(f"`{name}` must be a positive finite number, got {x!r}")
    return v


def _per_speed(value: Any, n: int, components: Sequence[str] | None, name: str) -> np.ndarray:
    """One 6x6 matrix per speed from a table (or one value for every speed)."""
    a = np.asarray(value, dtype=float)
    if a.ndim == 0:
        return np.array([expand_matrix(float(a), components, name)] * n)
    if a.shape[0] != n:
        raise ModelError(f"`{name}`: give one entry per speed ({n}), got {a.shape[0]}")
    return np.array([expand_matrix(x, components, f"{name}[{i}]") for i, x in enumerate(a)])


def _per_element(x: Any, n: int, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float).ravel()
    if a.size == 1:
        a = np.full(n, a[0])
    if a.size != n or not np.all(np.isfinite(a)) or np.any(a < 0):
        raise ModelError(f"`{name}` must be one value or one per element ({n}), >= 0")
    return a
