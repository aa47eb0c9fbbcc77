"""Sparse assembly of element :class:`~rheolin.mechanics._term.Term` objects.

Each term holds small dense Fourier coefficients on its global DOFs; assembly collects COO
triplets per (matrix, harmonic) and returns SciPy CSR matrices. Never dense ``N x N``.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, replace
from fractions import Fraction
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp

from ..errors import ModelError
from ..system import PeriodicSystem
from ._term import Term
from .gears import gear_mesh_term, line_of_action
from .joints import COMPONENTS, coupling_term
from .loads import gravity_load, harmonic_force_term
from .speeds import SpeedPlan, propagate_speeds, speed_plan

if TYPE_CHECKING:
    from .model import Model

__all__ = ["Assembled", "assemble_coefficients", "assemble_model", "assemble_system"]

_Coefficients = tuple[
    dict[int, sp.csr_array], dict[int, sp.csr_array], dict[int, sp.csr_array], dict[int, np.ndarray]
]


def assemble_coefficients(terms: Iterable[Term], n_dof: int) -> _Coefficients:
    """Sum terms into sparse ``M_k, D_k, K_k`` and dense ``f_k`` on ``n_dof`` global DOFs.

    Returns
    -------
    (M, D, K, f)
        Dicts from harmonic index to ``csr_array`` (``n_dof x n_dof``) or vector. Harmonic 0 is
        real; for ``k != 0`` both signs are returned as they were given by the terms.

    Examples
    --------
    >>> import numpy as np
    >>> spring = Term(np.array([0, 1]), K={0: np.array([[1.0, -1.0], [-1.0, 1.0]])})
    >>> M, D, K, f = assemble_coefficients([spring, Term(np.array([1]), K={0: np.eye(1)})], 2)
    >>> K[0].toarray()
    array([[ 1., -1.],
           [-1.,  2.]])
    """
    triplets: dict[str, dict[int, tuple[list, list, list]]] = {"M": {}, "D": {}, "K": {}}
    loads: dict[int, np.ndarray] = {}
    for term in terms:
        dofs = np.asarray(term.dofs, dtype=np.int64).ravel()
        d = dofs.size
        if d and (dofs.min() < 0 or dofs.max() >= n_dof):
            raise ModelError(f"term DOF indices must lie in [0, {n_dof}), got {dofs}")
        rows = np.repeat(dofs, d)
        cols = np.tile(dofs, d)
        for name in ("M", "D", "K"):
            for k, x in getattr(term, name).items():
                x = np.asarray(x)
                if x.shape != (d, d):
                    raise ModelError(
                        f"term `{name}[{k}]` must have shape ({d}, {d}), got {x.shape}"
                    )
                r, c, v = triplets[name].setdefault(int(k), ([], [], []))
                r.append(rows)
                c.append(cols)
                v.append(x.ravel())
        for k, vec in term.f.items():
            fk = np.asarray(vec).ravel()
            if fk.shape != (d,):
                raise ModelError(f"term `f[{k}]` must have shape ({d},), got {fk.shape}")
            out = loads.setdefault(int(k), np.zeros(n_dof, dtype=complex))
            np.add.at(out, dofs, fk)
    mats = []
    for name in ("M", "D", "K"):
        table: dict[int, sp.csr_array] = {}
        for k, (r, c, v) in sorted(triplets[name].items()):
            data = np.concatenate(v)
            data = data.real.astype(float) if k == 0 else data.astype(complex)
            mat = sp.coo_array(
                (data, (np.concatenate(r), np.concatenate(c))), shape=(n_dof, n_dof)
            ).tocsr()
            mat.sum_duplicates()
            mat.eliminate_zeros()
            if mat.nnz:
                table[k] = mat
        mats.append(table)
    f = {k: (v.real.copy() if k == 0 else v) for k, v in sorted(loads.items()) if np.any(v != 0)}
    return mats[0], mats[1], mats[2], f


def assemble_system(terms: Iterable[Term], n_dof: int, omega: float) -> PeriodicSystem:
    """Assemble terms into a :class:`~rheolin.PeriodicSystem` with base frequency ``omega``.

    Examples
    --------
    >>> import numpy as np
    >>> s = assemble_system([Term(np.array([0]), M={0: np.eye(1)}, K={0: np.eye(1)},
    ...                           f={1: np.array([0.5]), -1: np.array([0.5])})], 1, 2.0)
    >>> s.n, s.load_harmonics
    (1, [-1, 1])
    """
    M, D, K, f = assemble_coefficients(terms, n_dof)
    return PeriodicSystem(omega=omega, M=M, D=D, K=K, f=f)


@dataclass
class Assembled:
    """A model assembled at one input speed (returned by ``Model.assemble``).

    Attributes
    ----------
    system
        The :class:`~rheolin.PeriodicSystem` (sparse coefficients).
    omega
        Base frequency ``w1`` [rad/s]; ``base_ratio`` is ``w1 / speed`` exactly.
    base_ratio
        ``w1 / speed`` as a Fraction.
    speed
        Input speed [rad/s].
    plan
        Speeds and integer harmonics (:class:`~rheolin.mechanics.speeds.SpeedPlan`).
    generators
        Harmonic generators for :meth:`rheolin.HarmonicSet.closure` (shaft, mesh, load).
    dof_labels
        ``(body, node, component)`` for every global DOF.
    node_index
        ``{(body, node): global node}``.
    joints
        ``{name: Term}`` of bearings and couplings.
    meshes
        ``{name: (Term, w, mesh harmonic)}`` of gear meshes (``delta = w^T q``).
    """

    system: PeriodicSystem
    omega: float
    base_ratio: Fraction
    speed: float
    plan: SpeedPlan
    generators: list[int]
    dof_labels: list[tuple[str, int, str]]
    node_index: dict[tuple[str, int], int]
    joints: dict[str, Term]
    meshes: dict[str, tuple[Term, np.ndarray, int]]

    def dofs(self, body: str, node: int) -> np.ndarray:
        """The six global DOFs of a node."""
        return 6 * self.node_index[(body, node)] + np.arange(6)


def model_speed_plan(model: Model) -> SpeedPlan:
    """Exact speed ratios, ``w1 / speed`` and integer harmonics of a :class:`Model`."""
    if not model.bodies:
        raise ModelError("the model has no bodies")
    inp = model.input_body or next(iter(model.bodies))
    if inp not in model.bodies:
        raise ModelError(f"`input_body`: no body named {inp!r}; bodies: {list(model.bodies)}")
    fixed = {n: b.speed_ratio for n, b in model.bodies.items() if b.speed_ratio is not None}
    pairs = [m["pair"] for m in model.meshes.values()]
    ratios = propagate_speeds(inp, pairs, model.bodies, fixed)
    loads = [f["order"] * abs(ratios[f["reference"]]) for f in model.forces.values()]
    return speed_plan(inp, pairs, model.bodies, loads, fixed)


def assemble_model(model: Model, speed: float) -> Assembled:
    """Assemble a :class:`Model` at input speed ``speed`` [rad/s]."""
    plan = model_speed_plan(model)
    w1 = float(plan.base) * speed
    node_index: dict[tuple[str, int], int] = {}
    labels: list[tuple[str, int, str]] = []
    for b in model.bodies.values():
        for i in range(len(b.positions)):
            node_index[(b.name, i)] = len(node_index)
            labels += [(b.name, i, c) for c in COMPONENTS]
    dof = {key: 6 * v + np.arange(6) for key, v in node_index.items()}
    terms: list[Term] = []
    for b in model.bodies.values():
        s = plan.spin[b.name]
        if b.kind == "shaft":
            terms += _shaft_terms(b, s, w1, node_index[(b.name, 0)])
        elif b.kind == "condensed":
            local = b.data["condensed"]
            first = node_index[(b.name, 0)]
            placed = replace(local, nodes=[first + i for i in local.nodes])
            terms.append(placed.term(b.axis, s, w1))
        for i, rn in b.disks.items():
            terms.append(rn.term(node_index[(b.name, i)], b.axis, s, w1))
    joints: dict[str, Term] = {}
    for name, j in model.joints.items():
        other = None if j["other"][0] is None else dof[j["other"]]
        frame = j["frame"]
        s = 0 if frame is None else plan.spin[frame]
        axis = (0.0, 0.0, 1.0) if frame is None else model.bodies[frame].axis
        joints[name] = coupling_term(
            dof[(j["body"], j["node"])], other, j["K"], j["D"], spin=s, axis=axis, omega=w1
        )
    meshes: dict[str, tuple[Term, np.ndarray, int]] = {}
    for (name, g), harmonic in zip(model.meshes.items(), plan.mesh, strict=True):
        w = _mesh_vector(model, g, plan)
        dof_a = dof[(g["pair"].pinion_body, g["pinion_node"])]
        dof_b = dof[(g["pair"].gear_body, g["gear_node"])]
        t = gear_mesh_term(
            dof_a, dof_b, w, harmonic, g["stiffness"], g["damping"], g["transmission_error"]
        )
        meshes[name] = (t, w, harmonic)
    for f in model.forces.values():
        n = plan.harmonic(f["order"] * abs(plan.ratios[f["reference"]]))
        terms.append(
            harmonic_force_term(dof[(f["body"], f["node"])], f["force"], f["moment"], n, f["phase"])
        )
    all_terms = terms + list(joints.values()) + [m[0] for m in meshes.values()]
    M, D, K, fl = assemble_coefficients(all_terms, 6 * len(node_index))
    if model.gravity is not None:
        for k, v in gravity_load(M, model.gravity, len(node_index)).items():
            fl[k] = fl[k] + v if k in fl else v
    system = PeriodicSystem(omega=w1, M=M, D=D, K=K, f=fl)
    return Assembled(
        system, w1, plan.base, speed, plan, plan.generators, labels, node_index, joints, meshes
    )


def _mesh_vector(model: Model, g: dict[str, Any], plan: SpeedPlan) -> np.ndarray:
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


def _shaft_terms(body: Any, s: int, w1: float, first_node: int) -> list[Term]:
    """Timoshenko elements (M1's ``beam_term``) between consecutive nodes of a shaft body."""
    from .beam import beam_term

    data = body.data
    return [
        beam_term(
            (first_node + i, first_node + i + 1),
            float(length),
            section,
            data["material"],
            body.axis,
            body.axis,
            s,
            w1,
            y_axis=data.get("y_axis"),
        )
        for i, (length, section) in enumerate(zip(data["lengths"], data["sections"], strict=True))
    ]
