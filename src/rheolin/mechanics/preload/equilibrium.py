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
   its nominal mean stiffness, already in ``K_0``). Newton's method with the analytic
   sparse tangent ``K_0 + sum B^T K_t B + sum w w^T (k_t - k0)``, a backtracking line
   search on ``|r|``, and load stepping (the load factor halves after a failed step); where
   the tangent is singular (a bearing with clearance and nothing in contact yet) the step is
   regularized with the bearings' reference stiffness (Levenberg), which changes the path,
   not the equilibrium. Rigid links are eliminated as in the dynamics. Free rigid-body
   motions (the drive train's rotation) are held as the dynamics holds them
   (``R^T M_0 u = 0``, :mod:`rheolin.system.rigid_modes`); a ``"reaction"`` torque takes the value
   that balances the others on them, and any load left on them is reported.
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

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...errors import ModelError
from ...system.periodic import PeriodicSystem
from ...system.rigid_modes import find_rigid_modes
from ..assembly import Assembled
from ..items import ModelData, positive
from ..rolling import MeshLoadLaw, RollingLaw
from ..rotation import transverse_basis
from ..template import assemble_model
from .linearize import base_model, linearized_model
from .state import BearingState, MeshState, OperatingPoint

__all__ = ["LoadedMesh", "RollingJoint", "StaticEquilibrium", "operating_point"]

#: Newton: relative residual of a converged equilibrium, iterations per load step, and the
#: smallest load step before giving up.
RTOL = 1e-10
MAX_ITERATIONS = 60
MIN_STEP = 1.0 / 4096

#: A static deflection beyond this fraction of the model's size is not a small-deflection
#: operating point (the linear theory of every joint and body is void there).
MAX_DEFLECTION = 1e-2


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
        y, iterations, steps = self.load_stepping()
        u = np.asarray(self.T @ y)
        r_end, _ = self.residual(y, 1.0, False)
        residual = float(np.linalg.norm(self.weight * r_end)) / self.scale
        _plausible(self.model, self.bearings, u, self.a)
        bstates, mstates = self.joint_states(u)
        damping = {j.name: j.damping * (j.plane @ j.plane.T) for j in self.bearings}
        lin = linearized_model(self.model, bstates, damping, mstates, self.torques)
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
        rigid = find_rigid_modes(reduced)
        if rigid is not None:
            self.T = sp.csr_array(T1 @ rigid.transform())
            self.R = T1 @ rigid.modes  # rigid modes over every DOF
        else:
            self.T, self.R = T1, np.zeros((n, 0))

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
                    f"reaction torques {reactions}: they do not act on independent free "
                    "rotations of the drive train; give all but one of them a value [N m]"
                )
            self.torques.update({k: float(v) for k, v in zip(reactions, x, strict=True)})
            f0 = f0 + A @ x
        self.f0 = f0
        rigid_load = R.T @ f0 if R.size else np.zeros(0)
        if R.size:  # round-off of balanced torques is not a load
            floor = 1e-9 * (np.abs(R).T @ np.abs(f0))
            rigid_load = np.where(np.abs(rigid_load) > floor, rigid_load, 0.0)
        self.rigid_load = rigid_load

    def load_stepping(self) -> tuple[np.ndarray, int, int]:
        """The reduced equilibrium ``y`` by damped Newton over a growing load factor (halved
        after a failed step), with the Newton iterations and load steps taken."""
        self._reduced_operators()
        T = self.T
        guess = np.zeros(T.shape[1])
        try:  # a first guess: the linear problem with the joints' reference stiffness
            with np.errstate(all="ignore"):
                g = spla.splu(sp.csc_array(self.Kr + self.Kreg)).solve(self.fr)
            if np.all(np.isfinite(g)):
                guess = g
        except RuntimeError:
            pass
        y = guess
        lam, step = 0.0, 1.0
        iterations = steps = 0
        last: tuple[float, float] = (0.0, np.inf)
        while lam < 1.0:
            target = min(1.0, lam + step)
            start = y if lam > 0 else target * guess  # from the last equilibrium, else linear
            ok, y_new, its, res = _newton(
                self.residual, start, target, self.scale, self.Kreg, self.weight
            )
            iterations += its
            if ok:
                y, lam, steps = y_new, target, steps + 1
                step = min(2 * step, 1.0)
                continue
            last = (target, res)
            step /= 2
            if step < MIN_STEP:
                raise ModelError(_diagnose(self.model, self.bearings, T @ y_new, lam, last))
        return y, iterations, steps

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


def _newton(
    evaluate: Callable[[np.ndarray, float, bool], tuple[np.ndarray, Any]],
    y0: np.ndarray,
    lam: float,
    scale: float,
    Kreg: sp.csc_array,
    weight: np.ndarray,
) -> tuple[bool, np.ndarray, int, float]:
    """Damped Newton at load factor ``lam`` from ``y0``: ``(converged, y, iterations, |W r|)``
    (``W = diag(weight)``: residuals in consistent units)."""
    y = y0.copy()
    r, J = evaluate(y, lam, True)
    nr = float(np.linalg.norm(weight * r))
    absJ = abs(sp.csc_array(J))

    def tol(y: np.ndarray) -> float:
        # the load's scale, or round-off in the internal forces (stiff parts: |K| |y|)
        noise = 1e3 * np.finfo(float).eps * float(np.linalg.norm(weight * (absJ @ np.abs(y))))
        return max(RTOL * scale * lam, noise)

    for it in range(1, MAX_ITERATIONS + 1):
        if nr <= tol(y) or nr == 0.0:
            return True, y, it - 1, nr
        moved = False
        for mu in (0.0, 1e-6, 1e-3, 1.0):
            M = J if mu == 0.0 else J + mu * Kreg
            try:
                with np.errstate(all="ignore"):
                    dy = -spla.splu(sp.csc_array(M)).solve(r)
            except RuntimeError:  # singular
                continue
            if not np.all(np.isfinite(dy)):
                continue
            alpha = 1.0
            while alpha >= 1.0 / 256:
                yt = y + alpha * dy
                rt, Jt = evaluate(yt, lam, True)
                nt = float(np.linalg.norm(weight * rt))
                if nt < (1 - 1e-4 * alpha) * nr:
                    y, r, J, nr, moved = yt, rt, Jt, nt, True
                    break
                alpha /= 2
            if moved:
                break
        if not moved:
            return nr <= 10 * tol(y), y, it, nr
    return nr <= tol(y), y, MAX_ITERATIONS, nr


def _diagnose(
    model: ModelData,
    bearings: list[RollingJoint],
    u: np.ndarray,
    lam: float,
    last: tuple[float, float],
) -> str:
    """The message of a failed equilibrium, naming the joint most likely at fault."""
    target, res = last
    head = (
        f"static equilibrium not found: Newton stalled at {target:.1%} of the static load "
        f"(solved up to {lam:.1%}; residual {res:.3g} N)"
    )
    worst, why = None, ""
    for j in bearings:
        name, law = j.name, j.law
        d = j.B @ u
        r = float(np.hypot(*d))
        if law.in_contact(d) == 0:
            return (
                f"{head}; bearing {name!r} has no rolling element in contact (radial deflection "
                f"{r * 1e6:.3g} um, clearance {law.clearance * 1e6:.3g} um): nothing holds the "
                "shaft there. Reduce the clearance or add a support"
            )
        if worst is None or r > worst:
            worst, why = r, f"; bearing {name!r} deflects most ({r * 1e6:.3g} um)"
    meshes = [k for k, g in model.meshes.items() if g.get("load_law") is not None]
    if why:
        return head + why
    if meshes:
        return f"{head}; check the load law of mesh {meshes[0]!r}"
    return head


def _plausible(model: ModelData, bearings: list[RollingJoint], u: np.ndarray, a: Assembled) -> None:
    """Refuse an equilibrium the laws cannot vouch for: a table bearing beyond its table, or
    a deflection that is not small against the model (a joint that cannot carry its load lets
    the linear rest of the model find a far-away balance)."""
    for j in bearings:
        name, law = j.name, j.law
        if law.law == "table":
            assert law.deflection is not None and law.force_table is not None
            r = float(np.hypot(*(j.B @ u)))
            end = float(law.deflection[-1])
            if r > end * (1 + 1e-9):
                raise ModelError(
                    f"bearing {name!r} operates at {r * 1e6:.4g} um radial deflection, beyond "
                    f"its table (up to {end * 1e6:.4g} um, {law.force_table[-1]:.4g} N): it "
                    "cannot carry its load on the table; extend the table or check the load"
                )
    positions = np.concatenate([b.positions for b in model.bodies.values()])
    size = float(np.ptp(positions, axis=0).max()) if len(positions) > 1 else 0.0
    peak, where = 0.0, ("", -1)
    for key, i in a.node_index.items():
        v = float(np.linalg.norm(u[6 * i : 6 * i + 3]))
        if v > peak:
            peak, where = v, key
    if size > 0 and peak > MAX_DEFLECTION * size:
        worst = max(bearings, key=lambda j: float(np.hypot(*(j.B @ u))), default=None)
        blame = (
            f"; bearing {worst.name!r} deflects {float(np.hypot(*(worst.B @ u))) * 1e3:.4g} mm"
            if worst is not None
            else ""
        )
        raise ModelError(
            f"static equilibrium at an implausible deflection: {peak * 1e3:.4g} mm at "
            f"{where[0]} node {where[1]}, {peak / size:.3g} of the model's size{blame}: a "
            "joint cannot carry its load (a small-deflection operating point needs below "
            f"{MAX_DEFLECTION:.0%})"
        )
