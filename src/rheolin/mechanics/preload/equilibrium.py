"""The preloaded operating point: static equilibrium under torque, gravity and mean loads, and
the model linearized there (the paper's "kinetostatic relaxation" of the reference
trajectory).

A :class:`~rheolin.mechanics.model.Model` that declares torques (``add_torque``) or
load-dependent joints (``add_rolling_bearing``, a gear mesh with a ``load_law``) is solved
about its operating point:

1. **Static equilibrium.** With ``K_0`` the mean stiffness of the linear part of the model
   at the operating speed and ``f_0`` its mean load (gravity, static forces, torques, the
   mean transmission-error load), find ``u`` with

   ``r(u) = K_0 u - f_0 - sum_b B_b^T F_b(B_b u) + sum_m w_m (F_m(w_m^T u) - k0_m w_m^T u) = 0``

   (``B_b`` the radial relative motion of bearing ``b`` in its plane, ``F_b`` its force on
   the inner ring; ``w_m`` the line of action of mesh ``m``, ``F_m`` its force law, ``k0_m``
   its nominal mean stiffness, already in ``K_0``). A globalized Newton method
   (:mod:`.newton`): Newton directions, regularized with the joints' reference stiffness
   where the tangent is singular (a clearance, nothing in contact yet), and a line search on
   the energy along each direction, which crosses a clearance in one step; it finds the
   equilibrium wherever one exists, and where the energy keeps falling past any plausible
   deflection it refuses naming the joint that cannot carry the load and that load in N.
   Rigid links are eliminated as in the dynamics. Free rigid-body motions are held as the
   dynamics holds them (``R^T M_0 u = 0``, :mod:`rheolin.system.rigid_modes`) when they are
   a drive train's rotation or axial motion; a ``"reaction"`` torque takes the value that
   balances the others on them, and any load left on them is reported in N m or N. A
   motion nothing may hold (a body without lateral support) that the load pushes has no
   equilibrium: refused, naming the body and the direction.
2. **Linearization.** Each bearing becomes a linear joint with its tangent stiffness and a
   preload (``F(d_s) - K_t d_s``, so that the static force is exact); each mesh's stiffness
   function is scaled by ``k_t / k0`` and its static transmission error offset so that the
   mean mesh force stays ``F_s`` (the relative stiffness ripple, hence the loaded-TE
   excitation ``F_s k_j / k``, is kept). Torques become static moments. The linearized
   model's static response is the equilibrium ``u_s`` itself, and every solver, Campbell
   diagram and stability check works about it.

The static problem uses the mean (harmonic 0) stiffness; time-varying terms act about the
equilibrium in the dynamics.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from ...errors import ModelError
from ...system.periodic import PeriodicSystem
from ...system.rigid_modes import (
    FreeBodyError,
    find_rigid_modes,
    free_body_message,
    unheld_motions,
)
from ..assembly import Assembled
from ..items import ModelData, positive
from ..rolling import MeshLoadLaw, RollingLaw
from ..rotation import transverse_basis
from ..template import assemble_model
from . import checks
from .linearize import base_model, linearized_model
from .newton import Unbounded, minimize
from .state import BearingState, MeshState, OperatingPoint

__all__ = ["LoadedMesh", "RollingJoint", "StaticEquilibrium", "operating_point"]

#: Load steps of the fallback continuation, when the equilibrium under the whole load is
#: not found at once.
LOAD_STEPS = (0.125, 0.25, 0.5, 0.75, 1.0)
#: How far the line search may look for an equilibrium, in units of the largest plausible
#: deflection (:data:`~.checks.MAX_DEFLECTION` of the model's size; 1 mm for a point model).
SEARCH_REACH = 10.0


@dataclass
class RollingJoint:
    """A load-dependent bearing in the static problem: ``B`` (2 x n) takes the radial motion
    of its node relative to its support into the bearing ``plane`` (3 x 2)."""

    name: str
    law: RollingLaw
    B: sp.csr_array
    plane: np.ndarray
    damping: float  #: radial damping [N s/m]


@dataclass
class LoadedMesh:
    """A mesh with a load law in the static problem: its line of action ``w`` over every DOF
    (``delta = w^T u``) and its nominal mean stiffness."""

    name: str
    law: MeshLoadLaw
    w: np.ndarray
    nominal: float  #: k0 [N/m]


def _plane(axis: Any) -> np.ndarray:
    """The bearing plane's axes (3 x 2), right-handed about ``axis``: x and y for z."""
    a, b = transverse_basis(axis)
    return np.column_stack([-b, a])


def operating_point(model: ModelData, speed: float) -> OperatingPoint:
    """Static equilibrium of ``model`` at input ``speed`` [rad/s] and its linearization (see
    the module). Raises :class:`~rheolin.errors.ModelError` naming the joint when no
    equilibrium is found."""
    return StaticEquilibrium(model, speed).solve()


class StaticEquilibrium:
    """The static problem of a preloaded model at one speed, solved by :meth:`solve` in named
    steps: the joint operators, the reduction (rigid links, free rigid-body motions), the
    reaction torques, load stepping, and the joint states at the equilibrium.

    The linear part of the model is assembled at ``speed``: ``K0``, ``M0`` its mean stiffness
    and mass, ``f0`` its mean load, ``a`` the assembly (DOFs, meshes).
    """

    def __init__(self, model: ModelData, speed: float) -> None:
        self.model = model
        base = base_model(model)
        self.a: Assembled = assemble_model(base, positive(speed, "speed"))
        self.speed = float(speed)
        system = self.a.system
        n = self.n = system.n
        self.K0 = sp.csr_array(system.K[0]) if 0 in system.K else sp.csr_array((n, n))
        self.f0 = np.real(np.asarray(system.f.get(0, np.zeros(n)), dtype=complex))
        self.M0 = sp.csr_array(system.M[0]) if 0 in system.M else sp.csr_array((n, n))

    def solve(self) -> OperatingPoint:
        """The operating point: every step in turn (see the class)."""
        self.joint_operators()
        self.reduction()
        self.reaction_torques()
        y, iterations, steps = self.equilibrium()
        u = np.asarray(self.T @ y)
        r_end, _ = self.residual(y, 1.0, False)
        residual = float(np.linalg.norm(self.weight * r_end)) / self.scale
        checks.plausible(self.model, self.bearings, u, self.a)
        bstates, mstates = self.joint_states(u)
        damping = {j.name: j.damping * (j.plane @ j.plane.T) for j in self.bearings}
        lin = linearized_model(self.model, bstates, damping, mstates, self.torques)
        self.held_by_joints(lin, bstates)
        held = checks.held_loads(
            self.model, self.R, self.f0, self.a.dof_labels, self.a.node_index, self.torques
        )
        return OperatingPoint(
            speed=self.speed,
            displacement=u,
            dof_labels=self.a.dof_labels,
            node_index=self.a.node_index,
            bearings=bstates,
            meshes=mstates,
            torques=self.torques,
            rigid_load=np.asarray(self.rigid_load, dtype=float),
            iterations=iterations,
            load_steps=steps,
            residual=residual,
            model=lin,
            info={"held_loads": held},
        )

    def _dofs(self, body: str, node: int) -> np.ndarray:
        return np.asarray(self.a.dofs(body, node))

    # ------------------------------------------------------------------ the steps
    def joint_operators(self) -> None:
        """``B`` of every load-dependent bearing (radial relative motion in its plane) and the
        line of action of every mesh with a load law."""
        model, n = self.model, self.n
        self.bearings: list[RollingJoint] = []
        for name, b in model.rolling.items():
            E = _plane(model.bodies[b["body"]].axis)
            rows = [np.repeat([0, 1], 3)]
            cols = [np.tile(self._dofs(b["body"], b["node"])[:3], 2)]
            vals = [E.T.ravel()]
            if b["other"][0] is not None:
                rows.append(np.repeat([0, 1], 3))
                cols.append(np.tile(self._dofs(*b["other"])[:3], 2))
                vals.append(-E.T.ravel())
            B = sp.csr_array(
                (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(2, n)
            )
            self.bearings.append(RollingJoint(name, b["law"], B, E, b["damping"]))
        self.meshes: list[LoadedMesh] = []
        for name, g in model.meshes.items():
            if g.get("load_law") is None:
                continue
            term, w, _ = self.a.meshes[name]
            wv = np.zeros(n)
            np.add.at(wv, np.asarray(term.dofs), w)
            st = g["stiffness"]
            k0 = float(np.real(st.get(0, 0.0))) if isinstance(st, dict) else float(st)
            if not k0 > 0:
                raise ModelError(f"mesh {name!r}: a load law needs a positive mean stiffness")
            self.meshes.append(LoadedMesh(name, g["load_law"], wv, k0))

    def reduction(self) -> None:
        """``T``: the rigid links eliminated, then the free rigid-body motions ``R`` held as
        the dynamics holds them; ``Kjoints`` the bearings' reference stiffness (their
        tangent at 1 um), for the rigid-mode search, the first guess and the regularization
        of singular steps."""
        n, system = self.n, self.a.system
        T1 = sp.csr_array(
            system.constraint.transform()
            if system.constraint is not None
            else sp.identity(n, format="csr")
        )
        Kjoints = sp.csr_array((n, n))
        for j in self.bearings:
            Kjoints = Kjoints + j.law.reference_stiffness() * sp.csr_array(j.B.T @ j.B)
        self.Kjoints = Kjoints
        Kref = self.K0 + Kjoints
        reduced = PeriodicSystem(
            system.omega,
            M={0: sp.csc_array(T1.T @ self.M0 @ T1)},
            K={0: sp.csc_array(T1.T @ Kref @ T1)},
        )
        motions = system.motions
        if motions is not None and system.constraint is not None:
            motions = motions.through(T1)
        reduced.motions = motions
        rigid = find_rigid_modes(reduced)
        if rigid is not None:
            self.T = sp.csr_array(T1 @ rigid.transform())
            self.R = T1 @ rigid.modes  # rigid modes over every DOF
        else:
            self.T, self.R = T1, np.zeros((n, 0))
        self.free = unheld_motions(reduced, rigid)

    def reaction_torques(self) -> None:
        """Every torque's value: a ``"reaction"`` torque balances the others on the free
        rotations; the load left on them is ``rigid_load``."""
        model, R = self.model, self.R
        reactions = [k for k, t in model.torques.items() if isinstance(t["torque"], str)]
        A = np.zeros((self.n, len(reactions)))
        for j, k in enumerate(reactions):
            t = model.torques[k]
            axis = np.asarray(model.bodies[t["body"]].axis, float)
            A[self._dofs(t["body"], t["node"])[3:], j] = axis
        self.torques = {
            k: float(t["torque"])
            for k, t in model.torques.items()
            if not isinstance(t["torque"], str)
        }
        f0 = self.f0
        if reactions:
            if R.shape[1] == 0:
                raise ModelError(
                    f"torque {reactions[0]!r} = 'reaction': the model has no free rotation for "
                    "it to balance (a torsional support holds the drive train); give its value "
                    "[N m]"
                )
            G = R.T @ A
            x, *_ = np.linalg.lstsq(G, -(R.T @ f0), rcond=None)
            if np.linalg.matrix_rank(G, tol=1e-9 * max(np.abs(G).max(initial=0.0), 1e-300)) < len(
                reactions
            ):
                raise ModelError(
                    f"reaction torques {', '.join(repr(r) for r in reactions)}: they do not "
                    "act on independent free rotations of the drive train; give all but one "
                    "of them a value [N m]"
                )
            self.torques.update({k: float(v) for k, v in zip(reactions, x, strict=True)})
            f0 = f0 + A @ x
        self.f0 = f0
        rigid_load = R.T @ f0 if R.size else np.zeros(0)
        if R.size:  # round-off of balanced torques is not a load
            floor = 1e-9 * (np.abs(R).T @ np.abs(f0))
            rigid_load = np.where(np.abs(rigid_load) > floor, rigid_load, 0.0)
        self.rigid_load = rigid_load
        checks.unheld_with_load(self.free, f0, self.a.dof_labels)

    def equilibrium(self) -> tuple[np.ndarray, int, int]:
        """The reduced equilibrium ``y`` under the whole load by the globalized Newton method
        (:mod:`.newton`), from rest; should it stall or find the load uncarried along a search
        direction, by continuation over the load factor (:data:`LOAD_STEPS`). A refusal names
        the uncarried joint and its load (the first found) or else the out-of-balance force.
        Returns ``y``, the Newton iterations and the load steps."""
        self._reduced_operators()
        size = checks.model_size(self.model)
        reach = SEARCH_REACH * (checks.MAX_DEFLECTION * size if size > 0 else 1e-3)
        trans = np.array([c in ("ux", "uy", "uz") for _, _, c in self.a.dof_labels])

        def too_far(y: np.ndarray) -> bool:
            return float(np.abs(np.asarray(self.T @ y)[trans]).max(initial=0.0)) > reach

        y = np.zeros(self.T.shape[1])
        iterations = 0
        steps: tuple[float, ...] = (1.0,)
        unbounded = ""
        out = None
        for attempt in range(2):
            for k, lam in enumerate(steps):
                try:
                    out = minimize(
                        functools.partial(self.at_load, lam),
                        y,
                        self.Kreg + self.Kr,
                        self.weight,
                        self.scale * lam,
                        too_far,
                    )
                except Unbounded as exc:
                    # one search direction: the continuation below may still find a balance
                    u, d = np.asarray(self.T @ exc.y), np.asarray(self.T @ exc.direction)
                    unbounded = unbounded or checks.unbounded(
                        self.bearings, self.meshes, u, d, self.f0, reach / SEARCH_REACH
                    )  # the first found, with the whole load
                    out = None
                    break
                iterations += out.iterations
                if not out.converged:
                    break
                y = out.y
                if k == len(steps) - 1:
                    return y, iterations, len(steps)
            if attempt == 0:
                y, steps = np.zeros_like(y), LOAD_STEPS
        if unbounded:
            raise ModelError(unbounded)
        assert out is not None
        u = np.asarray(self.T @ out.y)
        raise ModelError(
            checks.stalled(self.bearings, self.meshes, u, self.force_residual(u), self.a.dof_labels)
        )

    def at_load(self, lam: float, y: np.ndarray, tangent: bool) -> tuple[np.ndarray, Any]:
        """:meth:`residual` at load factor ``lam`` (the argument order of :mod:`.newton`)."""
        return self.residual(y, lam, tangent)

    def force_residual(self, u: np.ndarray) -> np.ndarray:
        """The out-of-balance forces of every DOF at ``u`` [N, N m], less what the held rigid
        modes take (``M_0 R R^T r``: the drive, a thrust bearing)."""
        r = self.K0 @ u - self.f0
        for j in self.bearings:
            F, _ = j.law.force(j.B @ u)
            r = r - j.B.T @ F
        for m in self.meshes:
            d = float(m.w @ u)
            Fm, _ = m.law.force(d, m.nominal)
            r = r + m.w * (Fm - m.nominal * d)
        if self.R.size:
            r = r - self.M0 @ (self.R @ (self.R.T @ r))
        return np.asarray(r, dtype=float)

    def held_by_joints(self, lin: ModelData, bstates: dict[str, BearingState]) -> None:
        """Refuse an operating point whose linearized model leaves a body free where only a
        support can hold it: a rolling bearing that the static load does not close (no
        element in contact, no stiffness), or closes along one direction only."""
        weak = {}
        for k, b in bstates.items():
            kt = np.linalg.eigvalsh(0.5 * (b.stiffness + b.stiffness.T))
            if int(np.count_nonzero(kt > 1e-9 * max(float(kt.max()), 1e-300))) < 2:
                weak[k] = b
        if not weak:
            return
        a = assemble_model(lin, self.speed)
        system = a.system
        if system.constraint is not None:
            system = system.constraint.reduce(system)
        free = unheld_motions(system, find_rigid_modes(system))
        if not free:
            return
        laws = self.model.rolling
        why = []
        for k, b in weak.items():
            contact = (
                f"{b.in_contact} of {b.elements} elements in contact"
                if b.elements
                else ("in contact" if b.in_contact else "not in contact")
            )
            why.append(
                f"rolling bearing {k!r} has {contact} (radial deflection "
                f"{np.linalg.norm(b.deflection) * 1e6:.3g} um, clearance "
                f"{laws[k]['law'].clearance * 1e6:.3g} um): the static load "
                + ("does not close it" if not b.in_contact else "closes it along one direction")
            )
        raise FreeBodyError(
            free_body_message(free, why=" at the operating point: " + "; ".join(why))
        )

    def _reduced_operators(self) -> None:
        """The operators on the reduced unknowns ``u = T y``, the regularization ``Kreg`` and
        the residual weights."""
        T = self.T
        Tt = sp.csr_array(T.T)
        self.Kr = sp.csc_array(Tt @ self.K0 @ T)
        self.fr = Tt @ self.f0
        self.Br = [sp.csr_array(j.B @ T) for j in self.bearings]
        self.wr = [Tt @ m.w for m in self.meshes]
        self.ww: list[sp.csc_array] = []  # w w^T of each mesh, sparse
        for wj in self.wr:
            nz = np.flatnonzero(wj)
            self.ww.append(
                sp.csc_array(
                    (
                        np.outer(wj[nz], wj[nz]).ravel(),
                        (np.repeat(nz, nz.size), np.tile(nz, nz.size)),
                    ),
                    shape=(T.shape[1], T.shape[1]),
                )
            )
        Kreg = sp.csc_array(Tt @ self.Kjoints @ T)
        for m, Wj in zip(self.meshes, self.ww, strict=True):
            Kreg = Kreg + m.nominal * Wj
        self.Kreg = Kreg
        # residuals in consistent units (forces and moments): rows scaled by 1/sqrt(K_ii) of
        # the reference stiffness (an energy-like norm for the line search and the test)
        diag = np.abs((self.Kr + Kreg).diagonal())
        self.weight = 1.0 / np.sqrt(np.where(diag > 0, diag, max(diag.max(initial=0.0), 1.0)))
        self.scale = max(float(np.linalg.norm(self.weight * self.fr)), 1e-300)

    def residual(self, y: np.ndarray, lam: float, tangent: bool) -> tuple[np.ndarray, Any]:
        """``r(y)`` at load factor ``lam`` on the reduced unknowns, and its tangent when
        asked."""
        r = self.Kr @ y - lam * self.fr
        J = self.Kr.copy() if tangent else None
        for j, Bj in zip(self.bearings, self.Br, strict=True):
            F, Kt = j.law.force(Bj @ y)
            r = r - Bj.T @ F
            if tangent:
                J = J + sp.csc_array(Bj.T @ sp.csr_array(Kt) @ Bj)
        for m, wj, Wj in zip(self.meshes, self.wr, self.ww, strict=True):
            d = float(wj @ y)
            Fm, kt = m.law.force(d, m.nominal)
            r = r + wj * (Fm - m.nominal * d)
            if tangent and np.isfinite(kt):
                J = J + (kt - m.nominal) * Wj
        return r, J

    def joint_states(self, u: np.ndarray) -> tuple[dict[str, BearingState], dict[str, MeshState]]:
        """Each bearing's and mesh's deflection, force and operating stiffness at ``u``."""
        bstates: dict[str, BearingState] = {}
        for j in self.bearings:
            E = j.plane
            d2 = j.B @ u
            F2, Kt2 = j.law.force(d2)
            bstates[j.name] = BearingState(
                deflection=E @ d2,
                force=-(E @ F2),
                stiffness=E @ Kt2 @ E.T,
                in_contact=j.law.in_contact(d2),
                elements=int(j.law.elements) if j.law.law == "elements" else 0,
            )
        mstates: dict[str, MeshState] = {}
        for m in self.meshes:
            name, law, k0 = m.name, m.law, m.nominal
            d = float(m.w @ u)
            F, kt = law.force(d, k0)
            if F < 0:
                raise ModelError(
                    f"mesh {name!r} is loaded on its other flank (mean force {F:.4g} N): set "
                    "its `side` to the loaded flank, or reverse the torques"
                )
            if not (np.isfinite(kt) and kt > 0):
                raise ModelError(
                    f"mesh {name!r} carries no load ({F:.3g} N): its load law gives no stiffness"
                )
            ksec = F / d if d else law.k(0.0, k0)[0]
            mstates[name] = MeshState(force=F, deflection=d, secant=ksec, stiffness=kt, nominal=k0)
        return bstates, mstates
