"""Build a :class:`rheolin.mechanics.Model` from a validated model file (:mod:`rheolin.io.schema`).

The builder checks what the schema cannot see item by item: references between items (bodies,
nodes, the frame of a bearing), counts that depend on other fields (one diameter per element,
one coefficient matrix per speed), units per component pair of a joint matrix, and the gear
geometry; then it makes the ``Model.add_*`` calls. A problem is a :class:`rheolin.ModelError`
that starts with its field path (``shafts[1].bearings[0].stiffness``).
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ModelError
from ..mechanics.joints import COMPONENTS
from ..mechanics.model import Model
from ..mechanics.sections import MATERIALS, general_section
from .schema import Bearing, CondensedBody, ModelFile, Shaft, material_constant
from .units import UnitError, to_si

__all__ = ["CENTRE_DISTANCE_RTOL", "build_model"]

#: Relative tolerance between the centre distance of the gear nodes and ``m (z1 + z2) / 2``.
CENTRE_DISTANCE_RTOL = 0.03


def build_model(spec: ModelFile, base: Path) -> Model:
    """The :class:`~rheolin.mechanics.Model` a validated model file describes; relative file
    paths in it (condensed bodies) are taken from ``base``.

    >>> import tomllib
    >>> from pathlib import Path
    >>> from rheolin.data import example_text
    >>> spec = ModelFile.model_validate(tomllib.loads(example_text("rotor")))
    >>> m = build_model(spec, Path.cwd())
    >>> sorted(m.joints), len(m.bodies["rotor"].positions)
    (['drive_end', 'free_end'], 3)
    """
    return _Builder(spec, base).build()


def _joint_matrix(value: Any, components: list[str], kind: str, path: str) -> np.ndarray:
    """Scalar, vector (diagonal) or matrix with units checked per component pair."""
    trans = [c.startswith("u") for c in components]

    def unit_kind(i: int, j: int) -> str:
        base = {"stiffness": "stiffness", "damping": "damping", "mass": "mass_coefficient"}[kind]
        if trans[i] and trans[j]:
            return base
        if not trans[i] and not trans[j]:
            return "rotational_" + base
        return "cross_" + base

    def conv(x: Any, i: int, j: int, where: str) -> float:
        try:
            return to_si(x, unit_kind(i, j))
        except UnitError as exc:
            raise ModelError(f"{where}: {exc}") from None

    n = len(components)
    if not isinstance(value, list):
        kinds = {unit_kind(i, i) for i in range(n)}
        if isinstance(value, str) and len(kinds) > 1:
            raise ModelError(
                f"{path}: one value with units cannot serve translations and rotations "
                f"({', '.join(components)}); give a list, one per component"
            )
        return np.eye(n) * conv(value, 0, 0, path)
    if all(not isinstance(r, list) for r in value):
        if len(value) != n:
            raise ModelError(f"{path}: expected {n} values (one per component), got {len(value)}")
        return np.diag([conv(x, i, i, f"{path}[{i}]") for i, x in enumerate(value)])
    if len(value) != n or any(not isinstance(r, list) or len(r) != n for r in value):
        raise ModelError(f"{path}: expected a {n}x{n} matrix over components {components}")
    return np.array(
        [[conv(x, i, j, f"{path}[{i}][{j}]") for j, x in enumerate(r)] for i, r in enumerate(value)]
    )


def _vec3(value: Any, path: str) -> list[float] | None:
    """An offset: None, or 3 components (global x, y, z) [m]."""
    if value is None:
        return None
    if len(value) != 3:
        raise ModelError(f"{path}: must have 3 components (global x, y, z) [m]")
    return [float(v) for v in value]


def _preload(value: Any, path: str) -> list[float] | None:
    """A joint's preload: force (3) or force and moment (6), numbers (SI) or quantities."""
    if value is None:
        return None
    if not isinstance(value, list) or len(value) not in (3, 6):
        raise ModelError(f"{path}: give 3 forces or 3 forces and 3 moments, got {value!r}")
    out = []
    for i, x in enumerate(value):
        try:
            out.append(to_si(x, "force" if i < 3 else "moment"))
        except UnitError as exc:
            raise ModelError(f"{path}[{i}]: {exc}") from None
    return out


def _one(value: Any) -> Any:
    """A one-entry list as its value (per shaft), a longer one as is (per element)."""
    return value[0] if isinstance(value, list) and len(value) == 1 else value


def _table(value: Any, n: int, comps: list[str], kind: str, path: str) -> list[np.ndarray]:
    """One coefficient matrix per speed: a list of ``n`` entries, or one value for all."""
    if not isinstance(value, list):
        return [_joint_matrix(value, comps, kind, path)] * n
    if len(value) != n:
        raise ModelError(f"{path}: give one entry per speed ({n}), got {len(value)}")
    return [_joint_matrix(x, comps, kind, f"{path}[{i}]") for i, x in enumerate(value)]


class _Builder:
    def __init__(self, spec: ModelFile, base: Path) -> None:
        self.spec = spec
        self.base = base
        self.nodes: dict[str, int] = {}
        self.model = Model(
            input_body=spec.model.input_body,
            unbalance_reference=spec.model.unbalance_reference,
        )

    def build(self) -> Model:
        spec = self.spec
        bodies: list[tuple[str, Any]] = [(f"shafts[{i}]", b) for i, b in enumerate(spec.shafts)]
        bodies += [(f"rigid_bodies[{i}]", b) for i, b in enumerate(spec.rigid_bodies)]
        bodies += [(f"condensed_bodies[{i}]", b) for i, b in enumerate(spec.condensed_bodies)]
        if not bodies:
            raise ModelError("shafts: the model needs at least one shaft or rigid body")
        for path, b in bodies:
            if b.name in self.nodes:
                raise ModelError(f"{path}.name: a body named {b.name!r} already exists")
            if isinstance(b, CondensedBody) and b.positions is None:
                b.positions = self._file_positions(path, b)
            self.nodes[b.name] = len(b.positions) if hasattr(b, "positions") else 1
        if spec.model.input_body is not None:
            self._body(spec.model.input_body, "model.input_body")
        for path, b in bodies:
            self._call(path, self._add_body, path, b)
        for path, b in bodies:
            for i, d in enumerate(b.disks):
                self._node(b.name, d.node, f"{path}.disks[{i}].node")
                kw = d.model_dump(
                    exclude={"node", "material", "balance_grade", "balance_speed", "balance_mass"}
                )
                kw["density"] = self._disk_density(d, f"{path}.disks[{i}]", b)
                if d.balance_grade is not None:
                    kw["unbalance"] = self._graded(d, kw["density"], f"{path}.disks[{i}]")
                self._call(f"{path}.disks[{i}]", self.model.add_disk, b.name, d.node, **kw)
            for i, j in enumerate(b.bearings):
                if j.journal is None:
                    self._bearing(b.name, j, f"{path}.bearings[{i}]")
            for i, r in enumerate(b.rolling_bearings):
                p = f"{path}.rolling_bearings[{i}]"
                self._node(b.name, r.node, f"{p}.node")
                if (r.other_body is None) != (r.other_node is None):
                    raise ModelError(f"{p}.other_node: give `other_body` and `other_node` together")
                if r.other_body is not None:
                    assert r.other_node is not None
                    self._node(r.other_body, r.other_node, f"{p}.other_node", f"{p}.other_body")
                kw = r.model_dump(exclude={"name", "node", "stiffness"})
                self._call(p, self.model.add_rolling_bearing, r.name, b.name, r.node,
                           stiffness=r.stiffness or 0.0, **kw)  # fmt: skip
        for i, m in enumerate(spec.meshes):
            self._mesh(m, f"meshes[{i}]")
        for path, b in bodies:  # after the meshes: the sense each shaft turns is known
            for i, j in enumerate(b.bearings):
                if j.journal is not None:
                    self._journal(b.name, j, f"{path}.bearings[{i}]")
        for i, f in enumerate(spec.forces):
            p = f"forces[{i}]"
            self._node(f.body, f.node, f"{p}.node", f"{p}.body")
            if f.reference_body is not None:
                self._body(f.reference_body, f"{p}.reference_body")
            kw = f.model_dump(exclude={"name", "body", "node", "order"})
            for key, n in (("force", 3), ("moment", 3)):
                if len(kw[key]) != n:
                    raise ModelError(f"{p}.{key}: must have 3 components (global x, y, z)")
            kw["offset"] = _vec3(f.offset, f"{p}.offset")
            self._call(
                p, self.model.add_force, f.name, f.body, f.node, order=Fraction(f.order), **kw
            )
        for i, t in enumerate(spec.torques):
            p = f"torques[{i}]"
            self._node(t.body, t.node, f"{p}.node", f"{p}.body")
            self._call(p, self.model.add_torque, t.name, t.body, t.node, t.torque)
        for i, r in enumerate(spec.rigid_links):
            p = f"rigid_links[{i}]"
            self._node(r.body, r.node, f"{p}.node", f"{p}.body")
            self._node(r.other_body, r.other_node, f"{p}.other_node", f"{p}.other_body")
            comps = None if r.components in (None, "all") else list(r.components)
            self._call(p, self.model.add_rigid_link, r.name, r.body, r.node, r.other_body,
                       r.other_node, comps)  # fmt: skip
        if spec.rigid_links:  # conflicts and loops are found when the links are resolved
            self._call("rigid_links", self.model.speed_template)
        if spec.model.gravity is not None:
            self._call("model.gravity", self.model.set_gravity, spec.model.gravity)
        self._call("meshes", self.model.speed_plan)  # kinematic consistency of the gear train
        return self.model

    @staticmethod
    def _graded(d: Any, density: float, path: str) -> float:
        """The unbalance of a disk given by its ISO 21940-11 balance grade: the permissible
        residual unbalance ``m G / W`` with ``m`` its ``balance_mass`` (the rotor mass the
        grade is shared over; default the disk's own mass) and ``W`` its ``balance_speed``."""
        from ..mechanics.balance import iso21940_unbalance

        mass = d.balance_mass
        if mass is None:
            if d.mass is not None:
                mass = d.mass
            elif d.outer_diameter is not None and d.width is not None:
                mass = density * np.pi / 4 * (d.outer_diameter**2 - d.inner_diameter**2) * d.width
            else:
                raise ModelError(f"{path}.balance_mass: required for a disk without its own mass")
        try:
            return iso21940_unbalance(d.balance_grade, mass, d.balance_speed)
        except ModelError as exc:
            raise ModelError(f"{path}.balance_grade: {exc}") from None

    @staticmethod
    def _disk_density(d: Any, path: str, body: Any) -> float:
        """A disk given by its dimensions needs its density, or a named material (its own,
        else its shaft's)."""
        value = material_constant(d, "density")
        if value is None and d.material is None:
            value = material_constant(body, "density") if getattr(body, "material", None) else None
        if value is not None:
            return value
        if d.outer_diameter is not None or d.width is not None:
            raise ModelError(
                f"{path}.density: required for a disk given by `outer_diameter` and `width` "
                f'(or name a material, `material = "steel"`; known: {", ".join(MATERIALS)}); '
                "rheolin assumes no material"
            )
        return 0.0  # given by mass and inertia: the density is not used

    @staticmethod
    def _shaft_constants(b: Shaft, path: str) -> dict[str, Any]:
        """Elastic modulus, Poisson's ratio (unless the shear modulus is given), density:
        given (one value or one per element), or from a named material."""
        out: dict[str, Any] = {}
        for key in ("elastic_modulus", "poisson_ratio", "density"):
            if key == "poisson_ratio" and b.shear_modulus is not None:
                if b.poisson_ratio is not None:
                    out[key] = _one(b.poisson_ratio)
                continue
            value = getattr(b, key)
            value = _one(value) if value is not None else material_constant(b, key)
            if value is None:
                raise ModelError(
                    f'{path}.{key}: required (or name a material, `material = "steel"`; '
                    f"known: {', '.join(MATERIALS)}); rheolin assumes no material"
                )
            out[key] = value
        return out

    def _file(self, path: str, b: CondensedBody) -> Path:
        f = Path(b.path)
        f = f if f.is_absolute() else self.base / f
        if not f.is_file():
            raise ModelError(f"{path}.path: no such file {str(f)!r}")
        return f

    def _file_positions(self, path: str, b: CondensedBody) -> list[list[float]]:
        """Node positions stored in a condensed body's ``.npz`` (saved by ``condense``)."""
        try:
            with np.load(self._file(path, b)) as z:
                if "positions" in z.files:
                    return np.asarray(z["positions"], dtype=float).reshape(-1, 3).tolist()
        except (OSError, ValueError) as exc:
            raise ModelError(f"{path}.path: cannot read {b.path!r}: {exc}") from None
        raise ModelError(f"{path}.positions: required (the file has no `positions`)")

    def _add_body(self, path: str, b: Any) -> None:
        ratio = None if b.speed_ratio is None else Fraction(b.speed_ratio)
        if isinstance(b, Shaft):
            n_el = len(b.positions) - 1
            for key in ("outer_diameter", "inner_diameter"):
                v = getattr(b, key)
                if v is not None and len(v) not in (1, n_el):
                    raise ModelError(f"{path}.{key}: give one value or one per element ({n_el})")
            if (b.section is None) == (b.outer_diameter is None):
                raise ModelError(f"{path}: give exactly one of `outer_diameter` and `section`")
            if len(b.origin) != 3:
                raise ModelError(f"{path}.origin: must be a 3-vector of lengths")
            sec = None if b.section is None else general_section(**b.section.model_dump())
            for key in ("elastic_modulus", "density", "shear_modulus", "poisson_ratio",
                        "outer_diameter_right", "inner_diameter_right"):  # fmt: skip
                v = getattr(b, key)
                if isinstance(v, list) and len(v) not in (1, n_el):
                    raise ModelError(f"{path}.{key}: give one value or one per element ({n_el})")
            self.model.add_shaft(
                b.name,
                b.positions,
                outer_diameter=_one(b.outer_diameter),
                inner_diameter=_one(b.inner_diameter),
                **self._shaft_constants(b, path),
                material_damping=b.material_damping,
                axis=b.axis,
                origin=b.origin,
                section=sec,
                speed_ratio=ratio,
                shear_modulus=_one(b.shear_modulus),
                outer_diameter_right=_one(b.outer_diameter_right),
                inner_diameter_right=_one(b.inner_diameter_right),
            )
            for i, layer in enumerate(b.layers):
                kw = {k: _one(v) for k, v in layer.model_dump(exclude={"elements"}).items()}
                self._call(f"{path}.layers[{i}]", self.model.add_shaft_layer, b.name,
                           layer.elements, **kw)  # fmt: skip
        elif isinstance(b, CondensedBody):
            if not b.positions or any(len(x) != 3 for x in b.positions):
                raise ModelError(f"{path}.positions: give one 3-vector of lengths per node")
            f = self._file(path, b)
            self.model.add_condensed_body(
                b.name, b.positions, path=str(f), frame=b.frame, axis=b.axis, speed_ratio=ratio
            )
        else:
            if len(b.position) != 3:
                raise ModelError(f"{path}.position: must be a 3-vector of lengths")
            self.model.add_rigid_body(
                b.name, b.position, b.mass, np.array(b.inertia), b.axis, speed_ratio=ratio
            )

    def _bearing(self, body: str, j: Bearing, p: str) -> None:
        self._node(body, j.node, f"{p}.node")
        if (j.other_body is None) != (j.other_node is None):
            raise ModelError(f"{p}.other_node: `other_body` and `other_node` go together")
        if j.other_body is not None:
            self._node(j.other_body, j.other_node or 0, f"{p}.other_node", f"{p}.other_body")
        if j.frame is not None:
            self._body(j.frame, f"{p}.frame")
        comps: list[str] = list(COMPONENTS) if j.components == "all" else list(j.components)
        if len(set(comps)) != len(comps):
            raise ModelError(f"{p}.components: repeated component names")
        K: Any
        D: Any
        Ma: Any
        if j.speeds is None:
            K = _joint_matrix(j.stiffness, comps, "stiffness", f"{p}.stiffness")
            D = _joint_matrix(j.damping, comps, "damping", f"{p}.damping")
            Ma = _joint_matrix(j.mass, comps, "mass", f"{p}.mass")
        else:
            K, D, Ma = (
                np.array(_table(getattr(j, k), len(j.speeds), comps, k, f"{p}.{k}"))
                for k in ("stiffness", "damping", "mass")
            )
        for which, X in (("stiffness", K), ("damping", D)):
            if np.any(np.diagonal(X, axis1=-2, axis2=-1) < 0):
                raise ModelError(f"{p}.{which}: diagonal entries must be >= 0")
        self._call(
            p,
            self.model.add_bearing,
            j.name,
            body,
            j.node,
            K,
            D,
            comps,
            j.other_body,
            j.other_node,
            j.frame,
            mass=Ma,
            speeds=j.speeds,
            interpolation=j.interpolation,
            extrapolate=j.extrapolate,
            offset=_vec3(j.offset, f"{p}.offset"),
            other_offset=_vec3(j.other_offset, f"{p}.other_offset"),
            preload=_preload(j.preload, f"{p}.preload"),
        )

    def _journal(self, body: str, j: Bearing, p: str) -> None:
        """A plain journal bearing: its coefficient table over ``speeds`` by the short-bearing
        theory, for the sense its shaft turns (from the gear train)."""
        from ..mechanics.journal import journal_bearing_table

        self._node(body, j.node, f"{p}.node")
        g = j.journal
        assert g is not None
        if len(g.load_direction) != 3:
            raise ModelError(f"{p}.journal.load_direction: must have 3 components (x, y, z)")
        if any(w <= 0 for w in j.speeds or []):
            raise ModelError(f"{p}.speeds: a journal bearing's film needs speeds > 0")
        try:
            rotation = -1 if self.model.speed_plan().ratios[body] < 0 else 1
        except ModelError:
            rotation = 1
        try:
            Ks, Cs = journal_bearing_table(
                g.diameter, g.length, g.clearance, g.viscosity, g.load, j.speeds or [],
                axis=list(self.model.bodies[body].axis), load_direction=g.load_direction,
                rotation=rotation,
            )  # fmt: skip
        except ModelError as exc:
            raise ModelError(f"{p}.journal: {exc}") from None
        self._call(
            p,
            self.model.add_bearing,
            j.name,
            body,
            j.node,
            Ks,
            Cs,
            ["ux", "uy", "uz"],
            speeds=j.speeds,
            interpolation=j.interpolation,
            extrapolate=j.extrapolate,
            offset=_vec3(j.offset, f"{p}.offset"),
        )

    def _mesh(self, m: Any, p: str) -> None:
        self._node(m.pinion_body, m.pinion_node, f"{p}.pinion_node", f"{p}.pinion_body")
        self._node(m.gear_body, m.gear_node, f"{p}.gear_node", f"{p}.gear_body")
        if m.pinion_body == m.gear_body:
            raise ModelError(f"{p}.gear_body: must differ from pinion_body {m.pinion_body!r}")
        a, b = self.model.bodies[m.pinion_body], self.model.bodies[m.gear_body]
        xa, xb, e = a.positions[m.pinion_node], b.positions[m.gear_node], a.axis
        dist = float(np.linalg.norm((xb - xa) - e * np.dot(xb - xa, e)))
        nominal = m.module * (m.pinion_teeth + m.gear_teeth) / (2 * np.cos(m.helix_angle))
        if abs(dist - nominal) > CENTRE_DISTANCE_RTOL * nominal:
            raise ModelError(
                f"{p}.gear_teeth: tooth counts {m.pinion_teeth}+{m.gear_teeth} with module "
                f"{m.module * 1e3:g} mm need a centre distance of {nominal * 1e3:.4g} mm "
                f"(within {CENTRE_DISTANCE_RTOL:.0%}), but the gear nodes are "
                f"{dist * 1e3:.4g} mm apart"
            )
        stiff: Any = m.stiffness
        if stiff is None and None in (m.contact_ratio, m.single_stiffness, m.double_stiffness):
            raise ModelError(
                f"{p}.stiffness: give `stiffness` (mean), or `contact_ratio`, "
                "`single_stiffness` and `double_stiffness` (rectangular wave)"
            )
        te = {
            t.harmonic: (
                t.amplitude * np.cos(t.phase) if t.harmonic == 0
                else t.amplitude / 2 * np.exp(1j * t.phase)
            )
            for t in m.transmission_error
        }  # fmt: skip
        kw = m.model_dump(exclude={"name", "transmission_error", "stiffness"})
        self._call(
            p,
            self.model.add_gear_mesh,
            m.name,
            stiffness=stiff,
            transmission_error=te or None,
            **kw,
        )

    def _body(self, name: str, path: str) -> None:
        if name not in self.nodes:
            raise ModelError(f"{path}: no body named {name!r}; bodies: {list(self.nodes)}")

    def _node(self, body: str, node: int, path: str, body_path: str | None = None) -> None:
        self._body(body, body_path or path)
        if not 0 <= node < self.nodes[body]:
            raise ModelError(
                f"{path}: node {node} does not exist; body {body!r} has nodes "
                f"0..{self.nodes[body] - 1}"
            )

    @staticmethod
    def _call(path: str, fn: Any, *args: Any, **kw: Any) -> Any:
        try:
            return fn(*args, **kw)
        except ModelError as exc:
            if str(exc).startswith(path):  # already names its field
                raise ModelError(str(exc)) from None
            raise ModelError(f"{path}: {exc}") from None
