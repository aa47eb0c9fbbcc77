"""A model's planetary sets in its assembly: which bodies are in which carrier's frame, and
the sets' own terms (:class:`~rheolin.mechanics.template.SpeedTemplate` calls these).

Every planet is written in its set's carrier axes; with ``frame = "carrier"`` (the default) so
are the bodies of the set's sun, ring and carrier, and every body rigidly linked to them
(:mod:`rheolin.mechanics.carrier_frame` says why). Each element touching such a body is turned
exactly (:func:`~rheolin.mechanics.frames.in_frame`); outputs (bearing forces, mesh
deflections, displacements of those bodies) are turned back to global axes, the planets'
stay in their carrier's axes.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError
from ._term import SpeedTerm, Term
from .frames import frame_rotation, frame_vector, in_frame, inertial_rows
from .items import ModelData
from .planetary_terms import SetMesh, SetNodes, planetary_speed_terms
from .rotation import rotation_series
from .speeds import SpeedPlan

__all__ = [
    "Frames",
    "harmonic_generators",
    "model_frames",
    "refuse_in_frames",
    "set_meshes_for_output",
    "set_terms",
]

Series = dict[int, np.ndarray]


@dataclass
class Frames:
    """The DOF 3-blocks written in each set's carrier axes.

    Attributes
    ----------
    sets
        ``{set: (axis, carrier spin, blocks)}``.
    bodies
        ``{body: set}`` for every body in a carrier's frame (planets included).
    planet_bodies
        The planets.
    """

    sets: dict[str, tuple[np.ndarray, int, frozenset[int]]] = field(default_factory=dict)
    bodies: dict[str, str] = field(default_factory=dict)
    planet_bodies: tuple[str, ...] = ()
    _rotations: dict[int, Series] = field(default_factory=dict, repr=False)

    def __bool__(self) -> bool:
        return any(blocks for _, _, blocks in self.sets.values())

    def planets(self) -> list[str]:
        """The planet bodies."""
        return list(self.planet_bodies)

    def turn(self, term: SpeedTerm) -> SpeedTerm:
        """The term with its blocks in carrier frames written there."""
        for axis, spin, blocks in self.sets.values():
            term = in_frame(term, blocks, axis, spin)
        return term

    def outputs(self, term: SpeedTerm) -> SpeedTerm:
        """The term's force in global axes from the frames' DOFs (bearing forces)."""
        for axis, spin, blocks in self.sets.values():
            term = inertial_rows(term, blocks, axis, spin)
        return term

    def vector(self, w: np.ndarray, dofs: np.ndarray) -> np.ndarray | Series:
        """A deflection ``w^T q`` of inertial DOFs on the frames' DOFs: ``w`` itself when no
        frame touches them, else the series ``T(t)^T w``."""
        out: np.ndarray | Series = np.asarray(w)
        for axis, spin, blocks in self.sets.values():
            if not any(int(d) // 3 in blocks for d in dofs):
                continue
            if isinstance(out, dict):
                raise ModelError("a mesh between two carrier frames is not supported")
            out = frame_vector(out, dofs, blocks, axis, spin)
        return out

    def rotation(self, n_dof: int) -> Series:
        """``T(t)`` on every DOF (sparse series, kept): global axes = ``T`` times the DOFs."""
        if n_dof not in self._rotations:
            self._rotations[n_dof] = self._rotation(n_dof)
        return self._rotations[n_dof]

    def _rotation(self, n_dof: int) -> Series:
        out: Series = {}
        dofs = np.arange(n_dof)
        for axis, spin, blocks in self.sets.values():
            used = sorted({3 * b + c for b in blocks for c in range(3)})
            if not used:
                continue
            T = frame_rotation(dofs[used], blocks, axis, spin)
            for k, X in T.items():
                coo = sp.coo_array(X)
                block = sp.coo_array(
                    (coo.data, (np.asarray(used)[coo.row], np.asarray(used)[coo.col])),
                    shape=(n_dof, n_dof),
                ).tocsr()
                out[k] = out[k] + block if k in out else block
        inert = np.ones(n_dof)
        for _, _, blocks in self.sets.values():
            for b in blocks:
                inert[3 * b : 3 * b + 3] = 0.0
        out[0] = out.get(0, sp.csr_array((n_dof, n_dof))) + sp.diags_array(inert).tocsr()
        return out

    def gravity(
        self, M: Mapping[int, Any], gravity: np.ndarray, n_dof: int, n_nodes: int
    ) -> Series:
        """``f = M~ g~(t)``: gravity on every node's translations (modal DOFs after the
        nodes carry none), turning in the frames' axes (``g~ = T^T g``), through the (turned)
        mass coefficients ``M~``."""
        field_: Series = {}
        base = np.zeros(n_dof, dtype=complex)
        base[: 6 * n_nodes] = np.tile(np.r_[np.asarray(gravity, dtype=float), 0, 0, 0], n_nodes)
        field_[0] = base
        for axis, spin, blocks in self.sets.values():
            R = rotation_series(axis, spin)
            for b in blocks:
                if b % 2:  # rotations carry no gravity
                    continue
                field_[0][3 * b : 3 * b + 3] = 0.0
                for k, P in R.items():
                    v = field_.setdefault(k, np.zeros(n_dof, dtype=complex))
                    v[3 * b : 3 * b + 3] += P.T @ gravity
        out: Series = {}
        for a, Ma in M.items():
            for b, gb in field_.items():
                v = Ma @ gb
                out[a + b] = out[a + b] + v if a + b in out else v
        return {k: (np.real(v) if k == 0 else v) for k, v in out.items() if np.any(v != 0)}


def harmonic_generators(model: ModelData, plan: SpeedPlan) -> list[int]:
    """The plan's generators without the planets' spins: an axisymmetric planet in its
    carrier's axes adds no harmonic of its own (its mesh frequencies are the set's)."""
    planets = {b for s in model.planetary.values() for b in s.planets}
    if not planets:
        return plan.generators
    others = {abs(s) for b, s in plan.spin.items() if b not in planets}
    drop = {abs(plan.spin[b]) for b in planets} - others
    return [g for g in plan.generators if g not in drop]


def refuse_in_frames(model: ModelData) -> None:
    """Refuse what a carrier frame cannot hold: a load-dependent bearing (its static load
    turns there) or speed-dependent coefficients on a body in a carrier frame."""
    _refuse(model, _owners(model))


def model_frames(model: ModelData, plan: SpeedPlan, dof: Mapping[tuple[str, int], np.ndarray]
                 ) -> Frames:  # fmt: skip
    """Which bodies are in which set's carrier frame, checked against what a frame cannot
    hold (load-dependent joints, speed tables, links across frames)."""
    frames = Frames()
    owner = _owners(model)
    _refuse(model, owner)
    for name, s in model.planetary.items():
        e = model.bodies[s.carrier[0]].axis
        blocks: set[int] = set()
        for body, f in owner.items():
            if f != name:
                continue
            for i in range(len(model.bodies[body].positions)):
                d = dof[(body, i)]
                blocks |= {int(d[0]) // 3, int(d[3]) // 3}
        frames.sets[name] = (e, plan.spin[s.carrier[0]], frozenset(blocks))
    frames.bodies = owner
    frames.planet_bodies = tuple(p for s in model.planetary.values() for p in s.planets)
    return frames


def _owners(model: ModelData) -> dict[str, str]:
    """``{body: set}`` of the bodies in a carrier frame: planets, the members of sets written
    in their carrier's axes (the first set claims a shared member), and bodies rigidly linked
    to them."""
    owner: dict[str, str] = {}
    for name, s in model.planetary.items():
        for p in s.planets:
            owner[p] = name
        if s.frame == "carrier":
            for body, _ in (s.sun, s.ring, s.carrier):
                owner.setdefault(body, name)
    changed = True
    while changed:  # bodies rigidly linked to a body in a frame join it
        changed = False
        for lname, link in model.links.items():
            a, b = link["body"], link["other_body"]
            fa, fb = owner.get(a), owner.get(b)
            if fa == fb:
                continue
            if fa is not None and fb is not None:
                raise ModelError(
                    f"rigid link {lname!r} joins bodies in two carrier frames ({fa!r}, {fb!r})"
                )
            if (a in model.bodies and model.bodies[a].kind == "planet") or (
                b in model.bodies and model.bodies[b].kind == "planet"
            ):
                raise ModelError(f"rigid link {lname!r}: a planet cannot be linked rigidly")
            owner[a if fa is None else b] = fa if fa is not None else fb  # type: ignore[assignment]
            changed = True
    for lname, link in model.links.items():
        f = owner.get(link["body"])
        if f is None:
            continue
        e = model.bodies[model.planetary[f].carrier[0]].axis
        pa = model.bodies[link["body"]].positions[link["node"]]
        pb = model.bodies[link["other_body"]].positions[link["other_node"]]
        r = np.asarray(pb, float) - np.asarray(pa, float)
        if np.linalg.norm(r - (r @ e) * e) > 1e-9 * max(1.0, float(np.linalg.norm(r))):
            raise ModelError(
                f"rigid link {lname!r} in the carrier frame of {f!r} must join nodes on one "
                "line along the carrier's axis"
            )
    return owner


def _refuse(model: ModelData, owner: Mapping[str, str]) -> None:
    for name, r in model.rolling.items():
        for body in (r["body"], r["other"][0]):
            if body in owner:
                raise ModelError(
                    f"rolling bearing {name!r}: body {body!r} is in the carrier frame of "
                    f"{owner[body]!r}, where its static load turns; give the set "
                    '`frame = "inertial"`'
                )
    for name, j in model.joints.items():
        if j.get("table") is not None and (j["body"] in owner or j["other"][0] in owner):
            raise ModelError(
                f"bearing {name!r}: speed-dependent coefficients on a body in a carrier frame "
                'are not supported; give the set `frame = "inertial"`'
            )


def set_terms(
    model: ModelData,
    plan: SpeedPlan,
    dof: Mapping[tuple[str, int], np.ndarray],
    frames: Frames,
) -> tuple[list[SpeedTerm], dict[str, SetMesh]]:
    """Every set's planet bearings, meshes and orbit loads (the planets' inertia comes with
    their bodies), with each member coupled from the frame it is written in."""
    terms: list[SpeedTerm] = []
    meshes: dict[str, SetMesh] = {}
    for name, s in model.planetary.items():
        refs = {"sun": s.sun, "ring": s.ring, "carrier": s.carrier}
        e = model.bodies[s.carrier[0]].axis
        placed = {k: (dof[ref], model.bodies[ref[0]].positions[ref[1]]) for k, ref in refs.items()}
        nodes = SetNodes(
            placed["sun"],
            placed["ring"],
            placed["carrier"],
            [dof[(p, 0)] for p in s.planets],
            e,
            s.reference,
        )
        s_c = plan.spin[s.carrier[0]]
        turn = {}
        for k, (b, _) in refs.items():
            f = frames.bodies.get(b)
            turn[k] = s_c - (0 if f is None else frames.sets[f][1])
            if f is not None and f != name and float(frames.sets[f][0] @ e) < 1 - 1e-9:
                raise ModelError(f"planetary set {name!r}: its {k} is in the frame of a set "
                                 f"on another axis ({f!r})")  # fmt: skip
        spins = {k: plan.spin[b] for k, (b, _) in refs.items()}
        spins["planet"] = plan.spin[s.planets[0]]
        t, m = planetary_speed_terms(
            name, s.geometry, nodes, s.planet, s.sun_mesh, s.ring_mesh, spins,
            plan.sets[name], s.side, s.ring_phase, turn, inertia=False,
        )  # fmt: skip
        terms += t
        meshes.update(m)
    return terms, meshes


def set_meshes_for_output(meshes: Mapping[str, SetMesh]) -> dict[str, tuple[Term, Any, int]]:
    """The sets' meshes as :class:`~rheolin.mechanics.assembly.Assembled` lists them:
    ``(term, vector, harmonic)`` with the deflection ``delta(t) = sum_k g_k^T q``."""
    out = {}
    for name, m in meshes.items():
        vec = m.vector
        keys = [k for k, v in vec.items() if np.any(v)]
        w: Any = np.real(vec[0]) if keys == [0] else vec
        out[name] = (m.term.at(0.0), w, m.harmonic)
    return out
