"""A model assembled once for every speed: :class:`SpeedTemplate`.

The input speed enters the periodic system only through ``w1 = base_ratio * speed``, and every
coefficient is a polynomial of degree <= 2 in ``w1`` (gyroscopic and circulatory terms are
linear, centripetal ones quadratic, docs/rotating-bodies.md) whose harmonic indices do not
depend on the speed. The template reads the model once, sums every element's
:class:`~rheolin.mechanics._term.SpeedTerm` into one CSR pattern per (matrix, harmonic) with one
row of values per power of ``w1``, and at each speed forms ``X^(0) + w1 X^(1) + w1^2 X^(2)`` on
those patterns: one vector operation per coefficient instead of rebuilding the elements.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ..errors import ModelError
from ..system.constraints import LinearConstraint
from ..system.frames import BodyFrame
from ..system.motions import Motions
from ..system.periodic import PeriodicSystem
from ._term import SpeedTerm, Term
from .assembly import Assembled
from .beam import beam_speed_term
from .bearing_table import SpeedTable
from .coefficients import POWERS, PolynomialCoefficient
from .gears import gear_mesh_term, line_of_action
from .items import ModelData
from .joints import COMPONENTS, coupling_speed_term, lever, pair_block
from .loads import gravity_load, harmonic_force_term
from .planetary_assembly import (
    harmonic_generators,
    model_frames,
    set_meshes_for_output,
    set_terms,
)
from .shaft import element_matrices
from .speeds import SpeedPlan, speed_plan, train_speeds

__all__ = ["SpeedTemplate", "assemble_model", "model_speed_plan"]


class SpeedTemplate:
    """A model (:class:`~rheolin.mechanics.items.ModelData`) assembled once, evaluated at any
    speed.

    The model is read when the template is made: change the model, make a new template.

    Examples
    --------
    >>> from rheolin.mechanics.model import Model
    >>> m = Model()
    >>> m.add_shaft("s", [0.0, 0.5, 1.0], outer_diameter=0.05, material="steel")
    >>> m.add_disk("s", 1, outer_diameter=0.3, width=0.05, unbalance=1e-4,
    ...            material="steel")
    >>> m.add_bearing("a", "s", 0, 1e7, 1e2); m.add_bearing("b", "s", 2, 1e7, 1e2)
    >>> t = SpeedTemplate(m)
    >>> a = t.assemble(300.0)
    >>> a.omega, a.system.load_harmonics
    (300.0, [-1, 1])
    >>> b = m.assemble(300.0)
    >>> bool(abs(a.system.D[0] - b.system.D[0]).max() <= 1e-12 * abs(b.system.D[0]).max())
    True
    """

    def __init__(self, model: ModelData) -> None:
        plan = model_speed_plan(model)
        self.plan = plan
        self.node_index: dict[tuple[str, int], int] = {}
        self.dof_labels: list[tuple[str, int, str]] = []
        for b in model.bodies.values():
            for i in range(len(b.positions)):
                self.node_index[(b.name, i)] = len(self.node_index)
                self.dof_labels += [(b.name, i, c) for c in COMPONENTS]
        self.n_dof = 6 * len(self.node_index)
        self.modal_dofs: dict[str, np.ndarray] = {}
        for b in model.bodies.values():  # modal DOFs of condensed bodies after every node
            modes = b.data["condensed"].n_modes if b.kind == "condensed" else 0
            if modes:
                self.modal_dofs[b.name] = self.n_dof + np.arange(modes)
                self.dof_labels += [(b.name, -1 - j, "mode") for j in range(modes)]
                self.n_dof += modes
        dof = {key: 6 * v + np.arange(6) for key, v in self.node_index.items()}
        self.frames = model_frames(model, plan, dof)
        self.generators = harmonic_generators(model, plan)
        self.constraint = _links(model, dof, self.n_dof)
        self.whirl_pairs = _planes(model, dof)
        self.motions = _motions(model, dof, self.dof_labels)
        # bodies in a carrier's axes are already in a rotating frame: no body frame on top
        self.body_frames = () if self.frames else _frames(model, dof, plan)
        terms = self._body_terms(model)
        self.joints: dict[str, SpeedTerm] = {}
        #: speed-dependent joints: name -> (table, |speed ratio| of its body, DOFs)
        self.tables: dict[str, tuple[SpeedTable, float, np.ndarray, tuple[Any, Any]]] = {}
        for name, j in model.joints.items():
            other = None if j["other"][0] is None else dof[j["other"]]
            frame = j["frame"]
            s = 0 if frame is None else plan.spin[frame]
            axis = (0.0, 0.0, 1.0) if frame is None else model.bodies[frame].axis
            levers = (lever(j.get("offset")), lever(j.get("other_offset")))
            self.joints[name] = coupling_speed_term(
                (dof[(j["body"], j["node"])], other), j["K"], j["D"], s, axis, j.get("M"), levers
            )
            pre = j.get("preload")
            if pre is not None:  # -T_a^T p on the node, +T_b^T p on the other one
                Ta, Tb = (np.eye(6) if t is None else t for t in levers)
                jt = self.joints[name]
                fvec = np.zeros(jt.dofs.size)
                fvec[:6] = -(Ta.T @ pre)
                if other is not None:
                    fvec[6:12] = Tb.T @ pre
                jt.f = {0: {0: fvec}}
            table = j.get("table")
            if table is not None:  # zeros now: the pattern; values per speed in `system`
                ratio = abs(float(plan.ratios[j["body"]]))
                jt = self.joints[name]
                z = {0: {0: np.zeros((jt.dofs.size, jt.dofs.size))}}
                self.joints[name] = SpeedTerm(jt.dofs, M=z, D=z, K=z)
                self.tables[name] = (table, ratio, np.asarray(jt.dofs), levers)
        self.meshes: dict[str, tuple[Term, Any, int]] = {}
        for (name, g), harmonic in zip(model.meshes.items(), plan.mesh, strict=True):
            w = _mesh_vector(model, g, plan)
            dof_a = dof[(g["pair"].pinion_body, g["pinion_node"])]
            dof_b = dof[(g["pair"].gear_body, g["gear_node"])]
            t = gear_mesh_term(
                dof_a, dof_b, w, harmonic, g["stiffness"], g["damping"], g["transmission_error"]
            )
            self.meshes[name] = (t, w, harmonic)
        for f in model.forces.values():
            n = plan.harmonic(f["order"] * abs(plan.ratios[f["reference"]]))
            term = harmonic_force_term(
                dof[(f["body"], f["node"])], f["force"], f["moment"], n, f["phase"]
            )
            terms.append(SpeedTerm.constant(term))
        terms += list(self.joints.values())
        terms += [SpeedTerm.constant(m[0]) for m in self.meshes.values()]
        sets, set_meshes = set_terms(model, plan, dof, self.frames)
        if self.frames:  # planetary sets: the frames' DOFs written in their carriers' axes
            terms = [self.frames.turn(t) for t in terms]
            self.joints = {n: self.frames.outputs(t) for n, t in self.joints.items()}
            self.meshes = {
                n: (t, self.frames.vector(w, t.dofs), h) for n, (t, w, h) in self.meshes.items()
            }
        self._collect(terms + sets)
        self.meshes.update(set_meshes_for_output(set_meshes))
        if model.gravity is not None:
            M = self._M.at(1.0)  # the mass matrix does not depend on the speed
            M.update({-k: x.conj() for k, x in M.items() if k})
            if self.frames:
                loads = self.frames.gravity(M, model.gravity, self.n_dof, len(self.node_index))
            else:
                loads = gravity_load(M, model.gravity, len(self.node_index))
            for k, v in loads.items():
                if k >= 0:
                    self._loads.setdefault(k, np.zeros((POWERS, self.n_dof), complex))[0] += v

    def _body_terms(self, model: ModelData) -> list[SpeedTerm]:
        terms: list[SpeedTerm] = []
        for b in model.bodies.values():
            s = self.plan.spin[b.name]
            first = self.node_index[(b.name, 0)]
            if b.kind == "shaft":
                data = b.data
                for i, (length, layers) in enumerate(
                    zip(data["lengths"], data["layers"], strict=True)
                ):
                    mats = element_matrices(float(length), layers, b.axis, data.get("y_axis"))
                    terms.append(beam_speed_term((first + i, first + i + 1), mats, b.axis, s))
            elif b.kind == "condensed":
                local = b.data["condensed"]
                placed = replace(
                    local,
                    nodes=[first + i for i in local.nodes],
                    modal_dofs=self.modal_dofs.get(b.name, ()),
                )
                terms.append(placed.speed_term(b.axis, s))
            for i, rn in b.disks.items():
                terms.append(rn.speed_term(self.node_index[(b.name, i)], b.axis, s))
        return terms

    def _collect(self, terms: list[SpeedTerm]) -> None:
        self._M, self._D, self._K = (PolynomialCoefficient(x, self.n_dof) for x in "MDK")
        self._loads: dict[int, np.ndarray] = {}
        for term in terms:
            dofs = np.asarray(term.dofs, dtype=np.int64).ravel()
            if dofs.size and (dofs.min() < 0 or dofs.max() >= self.n_dof):
                raise ModelError(f"term DOF indices must lie in [0, {self.n_dof}), got {dofs}")
            self._M.add(dofs, term.M)
            self._D.add(dofs, term.D)
            self._K.add(dofs, term.K)
            for p, series in term.f.items():
                for k, vec in series.items():
                    fk = np.asarray(vec).ravel()
                    if fk.shape != dofs.shape:
                        raise ModelError(
                            f"term `f[{k}]` must have shape ({dofs.size},), got {fk.shape}"
                        )
                    if k >= 0:
                        out = self._loads.setdefault(k, np.zeros((POWERS, self.n_dof), complex))
                        np.add.at(out[p], dofs, fk)
        for c in (self._M, self._D, self._K):
            c.freeze()
        self._slots = {
            name: {c.name: c.slots(d) for c in (self._M, self._D, self._K)}
            for name, (_, _, d, _) in self.tables.items()
        }

    def table_blocks(
        self, speed: float
    ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
        """``(dofs, K, D, M)`` of every speed-dependent joint at input ``speed`` [rad/s]
        (blocks on the joint's DOFs, node-to-node pairs expanded)."""
        out = []
        for _, (table, ratio, dofs, levers) in self.tables.items():
            K, D, M = table.at(ratio * speed)
            K, D, M = (pair_block(x, dofs.size == 12, levers) for x in (K, D, M))
            out.append((dofs, K, D, M))
        return out

    @property
    def time_invariant(self) -> bool:
        """True when no coefficient has a harmonic ``k != 0`` (at any speed)."""
        return not any(k for c in (self._M, self._D, self._K) for k in c.patterns)

    def mean_polynomials(self) -> dict[str, np.ndarray]:
        """Dense ``X_0^(p)`` of ``M, D, K`` (shape ``(3, n, n)``, power ``p`` of ``w1`` first).

        For batched solves of small time-invariant models over many speeds. Speed-dependent
        joints are not in it: add :meth:`table_blocks` at each speed.
        """
        out = {}
        for c in (self._M, self._D, self._K):
            X = np.zeros((POWERS, self.n_dof, self.n_dof))
            if 0 in c.patterns:
                rows, cols, values = c.patterns[0]
                X[:, rows, cols] = values
            out[c.name] = X
        return out

    def static_depends_on_speed(self) -> bool:
        """True when the static problem, the mean stiffness ``K_0`` and mean load ``f_0``,
        changes with the speed: a speed table, or a term in ``w1`` or ``w1^2`` in either."""
        K = self._K.patterns.get(0)
        still = not self.tables and (K is None or not np.any(K[2][1:]))
        f = self._loads.get(0)
        return not (still and (f is None or not np.any(f[1:])))

    def load_polynomials(self) -> dict[int, np.ndarray]:
        """``{k: f_k^(p)}`` for the load harmonics ``k >= 0`` (shape ``(3, n)`` each)."""
        return {k: v.copy() for k, v in self._loads.items()}

    def system(self, w1: float) -> PeriodicSystem:
        """The periodic system at base frequency ``w1`` [rad/s]."""
        f: dict[int, np.ndarray] = {}
        for k, (f0, f1, f2) in sorted(self._loads.items()):
            v = f0 + w1 * f1 + (w1 * w1) * f2
            if np.any(v != 0):
                f[k] = v.real.copy() if k == 0 else v
        extra: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {"K": [], "D": [], "M": []}
        if self.tables:
            speed = w1 / float(self.plan.base)
            for (_, K, D, M), slot in zip(
                self.table_blocks(speed), self._slots.values(), strict=True
            ):
                for key, X in (("K", K), ("D", D), ("M", M)):
                    extra[key].append((slot[key], X.ravel()))
        system = PeriodicSystem(
            omega=w1,
            M=self._M.at(w1, extra["M"]),
            D=self._D.at(w1, extra["D"]),
            K=self._K.at(w1, extra["K"]),
            f=f,
            constraint=self.constraint,
        )
        system.whirl_pairs = self.whirl_pairs
        system.motions = self.motions
        system.keep("body_frames", self.body_frames)
        return system

    def assemble(self, speed: float) -> Assembled:
        """The model at input speed ``speed`` [rad/s] (> 0), as ``Model.assemble`` gives it."""
        speed = float(speed)
        if not np.isfinite(speed) or speed <= 0:
            raise ModelError(f"`speed` must be a positive finite number, got {speed!r}")
        w1 = float(self.plan.base) * speed
        joints = {name: t.at(w1) for name, t in self.joints.items()}
        for (name, (_, _, dofs, _)), (_, K, D, M) in zip(
            self.tables.items(), self.table_blocks(speed), strict=True
        ):
            joints[name] = Term(dofs, M={0: M}, D={0: D}, K={0: K})
        return Assembled(
            self.system(w1),
            w1,
            self.plan.base,
            speed,
            self.plan,
            self.generators,
            self.dof_labels,
            self.node_index,
            joints,
            self.meshes,
            self.frames if self.frames else None,
        )


def model_speed_plan(model: ModelData) -> SpeedPlan:
    """Exact speed ratios, ``w1 / speed`` and integer harmonics of a model."""
    if not model.bodies:
        raise ModelError("the model has no bodies")
    inp = model.input_body or next(iter(model.bodies))
    if inp not in model.bodies:
        raise ModelError(f"`input_body`: no body named {inp!r}; bodies: {list(model.bodies)}")
    fixed = {n: b.speed_ratio for n, b in model.bodies.items() if b.speed_ratio is not None}
    pairs = [m["pair"] for m in model.meshes.values()]
    carried = [c for s in model.planetary.values() for c in s.constraints()]
    ratios = train_speeds(inp, pairs, model.bodies, fixed, carried)
    loads = [f["order"] * abs(ratios[f["reference"]]) for f in model.forces.values()]
    sets = {n: (s.sun[0], s.carrier[0], s.geometry.sun_teeth) for n, s in model.planetary.items()}
    return speed_plan(inp, pairs, model.bodies, loads, fixed, carried, sets)


def _planes(
    model: ModelData, dof: dict[tuple[str, int], np.ndarray]
) -> tuple[np.ndarray, np.ndarray] | None:
    """``(ix, iy)``: the (ux, uy) and (phix, phiy) DOFs of every node of the bodies along the
    global z axis (either sense), for gmres's whirl-pair preconditioner; None without any."""
    ix: list[int] = []
    iy: list[int] = []
    for b in model.bodies.values():
        if not np.allclose(np.abs(np.asarray(b.axis, float)), (0.0, 0.0, 1.0)):
            continue
        for i in range(len(b.positions)):
            d = dof[(b.name, i)]
            ix += [int(d[0]), int(d[3])]
            iy += [int(d[1]), int(d[4])]
    if not ix:
        return None
    return np.array(ix, dtype=np.int64), np.array(iy, dtype=np.int64)


def _frames(
    model: ModelData, dof: dict[tuple[str, int], np.ndarray], plan: SpeedPlan
) -> tuple[BodyFrame, ...]:
    """The rotating bodies' frames (:class:`rheolin.system.frames.BodyFrame`): spin, axis and
    node triples, for the stability check of large models (docs/stability.md)."""
    meshed = {
        b for m in model.meshes.values() for b in (m["pair"].pinion_body, m["pair"].gear_body)
    }
    out = []
    for b in model.bodies.values():
        s = plan.spin.get(b.name, 0)
        if s and len(b.positions):
            d = np.array([dof[(b.name, i)] for i in range(len(b.positions))])
            ax = np.asarray(b.axis, float)
            axis = (float(ax[0]), float(ax[1]), float(ax[2]))
            out.append(BodyFrame(b.name, int(s), axis, d.reshape(-1, 3), b.name in meshed))
    return tuple(out)


def _motions(
    model: ModelData, dof: dict[tuple[str, int], np.ndarray], labels: list[tuple[str, int, str]]
) -> Motions:
    """Each body's rigid motions (its axis, its nodes), for the solvers to tell the motions a
    steady state may hold (spin and axial) from those nothing holds (:mod:`rheolin.system.
    motions`)."""
    return Motions.of_bodies(
        {
            b.name: (b.axis, b.positions, [dof[(b.name, i)] for i in range(len(b.positions))])
            for b in model.bodies.values()
        },
        labels,
    )


def _links(
    model: ModelData, dof: dict[tuple[str, int], np.ndarray], n: int
) -> LinearConstraint | None:
    """The rigid links as one eliminated constraint ``q[pivots] = G q[keep]`` (chains of links
    substituted; a DOF constrained twice, or a loop, refused naming the links)."""
    if not model.links:
        return None
    slaves: dict[int, dict[int, float]] = {}
    owner: dict[int, str] = {}
    for name, link in model.links.items():
        pa = model.bodies[link["body"]].positions[link["node"]]
        pb = model.bodies[link["other_body"]].positions[link["other_node"]]
        T = lever(np.asarray(pb, float) - np.asarray(pa, float))
        T = np.eye(6) if T is None else T
        ma, sb = dof[(link["body"], link["node"])], dof[(link["other_body"], link["other_node"])]
        for comp in link["components"]:
            c = COMPONENTS.index(comp)
            s = int(sb[c])
            if s in slaves:
                raise ModelError(
                    f"rigid links {owner[s]!r} and {name!r} both constrain "
                    f"{link['other_body']} node {link['other_node']} {comp}"
                )
            slaves[s] = {int(ma[j]): float(T[c, j]) for j in range(6) if T[c, j] != 0.0}
            owner[s] = name
    for _ in range(len(slaves) + 1):  # chains: a master that is itself constrained
        changed = False
        for s, row in slaves.items():
            if not any(m in slaves for m in row):
                continue
            new: dict[int, float] = {}
            for m, v in row.items():
                for m2, v2 in (slaves[m] if m in slaves else {m: 1.0}).items():
                    new[m2] = new.get(m2, 0.0) + v * v2
            slaves[s] = new
            changed = True
        if not changed:
            break
    if any(m in slaves for row in slaves.values() for m in row):
        names = sorted({owner[s] for s in slaves})
        raise ModelError(f"rigid links {names} form a loop: a node cannot follow itself")
    pivots = np.array(sorted(slaves), dtype=np.int64)
    keep = np.setdiff1d(np.arange(n), pivots)
    col = {int(k): i for i, k in enumerate(keep)}
    G = np.zeros((pivots.size, keep.size))
    for i, s in enumerate(pivots):
        for m, v in slaves[int(s)].items():
            G[i, col[m]] += v
    return LinearConstraint(pivots=pivots, keep=keep, G=G, n=n)


def assemble_model(model: ModelData, speed: float) -> Assembled:
    """Assemble a model at input speed ``speed`` [rad/s]."""
    return SpeedTemplate(model).assemble(speed)


def _mesh_vector(model: ModelData, g: dict[str, Any], plan: SpeedPlan) -> np.ndarray:
    """Line of action from normal module, pressure and helix angle and the node positions."""
    p = g["pair"]
    bp, bg = model.bodies[p.pinion_body], model.bodies[p.gear_body]
    if abs(abs(bp.axis @ bg.axis) - 1) > 1e-9:
        raise ModelError("gear mesh: pinion and gear axes must be parallel")
    beta = g["helix_angle"]
    alpha_t = np.arctan(np.tan(g["pressure_angle"]) / np.cos(beta))
    mt = g["module"] / np.cos(beta)
    rb1 = mt * p.pinion_teeth / 2 * np.cos(alpha_t)
    rb2 = mt * p.gear_teeth / 2 * np.cos(alpha_t)
    xa, xb, e = bp.positions[g["pinion_node"]], bg.positions[g["gear_node"]], bp.axis
    dist = float(np.linalg.norm((xb - xa) - e * np.dot(xb - xa, e)))
    alpha = alpha_t
    if dist > 1e-12:
        if dist <= rb1 + rb2:
            raise ModelError(
                f"gear mesh: centre distance {dist:.6g} m must exceed the sum of base radii "
                f"{rb1 + rb2:.6g} m (check `module` and the tooth counts)"
            )
        alpha = float(np.arccos((rb1 + rb2) / dist))  # working transverse pressure angle
    sign = int(np.sign(plan.spin[p.pinion_body])) or 1
    return line_of_action(xa, xb, e, rb1, rb2, alpha, beta, sign * g["side"], g["center_direction"])
