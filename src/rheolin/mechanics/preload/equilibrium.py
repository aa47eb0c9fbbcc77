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
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...errors import ModelError
from ...system.periodic import PeriodicSystem
from ...system.rigid_modes import find_rigid_modes
from ..joints import COMPONENTS
from ..rotation import transverse_basis

__all__ = ["BearingState", "MeshState", "OperatingPoint", "operating_point", "preloaded_template"]

#: Newton: relative residual of a converged equilibrium, iterations per load step, and the
#: smallest load step before giving up.
RTOL = 1e-10
MAX_ITERATIONS = 60
MIN_STEP = 1.0 / 4096


@dataclass
class BearingState:
    """A load-dependent bearing at the operating point (global axes)."""

    deflection: np.ndarray  #: radial deflection of the node relative to its support [m] (3)
    force: np.ndarray  #: force on the support [N] (3)
    stiffness: np.ndarray  #: tangent (operating) stiffness [N/m] (3 x 3)
    in_contact: int  #: rolling elements in contact (1/0 for lumped laws)
    elements: int  #: rolling elements (0 for lumped laws)

    @property
    def load(self) -> float:
        return float(np.linalg.norm(self.force))


@dataclass
class MeshState:
    """A load-dependent gear mesh at the operating point (line of action)."""

    force: float  #: mean mesh force [N]
    deflection: float  #: mean mesh deflection [m]
    secant: float  #: k(F) [N/m]
    stiffness: float  #: tangent (operating) stiffness dF/d delta [N/m]
    nominal: float  #: nominal mean stiffness k0 [N/m]


@dataclass
class OperatingPoint:
    """Static equilibrium of a preloaded model and the model linearized there."""

    speed: float
    displacement: np.ndarray  #: static displacement of every DOF
    dof_labels: list[tuple[str, int, str]]
    node_index: dict[tuple[str, int], int]
    bearings: dict[str, BearingState]
    meshes: dict[str, MeshState]
    torques: dict[str, float]  #: every torque [N m], reactions computed
    rigid_load: np.ndarray  #: load left on the free rigid-body motions (R^T f), held
    iterations: int
    load_steps: int
    residual: float  #: relative residual of the equilibrium
    model: Any  #: the linearized :class:`~rheolin.mechanics.model.Model`
    info: dict[str, Any] = field(default_factory=dict)

    def node_displacement(self, body: str, node: int) -> np.ndarray:
        """``(ux, uy, uz, phix, phiy, phiz)`` of a node at the operating point."""
        i = self.node_index[(body, node)]
        return self.displacement[6 * i : 6 * i + 6].copy()

    def max_displacement(self) -> tuple[float, tuple[str, int]]:
        """The largest translation [m] of any node, and where."""
        best, where = 0.0, ("", -1)
        for key, i in self.node_index.items():
            v = float(np.linalg.norm(self.displacement[6 * i : 6 * i + 3]))
            if v > best:
                best, where = v, key
        return best, where

    def to_dict(self) -> dict[str, Any]:
        """A JSON-able summary (SI units)."""
        peak, (body, node) = self.max_displacement()
        return {
            "speed_rad_s": self.speed,
            "max_displacement_m": peak,
            "max_displacement_at": {"body": body, "node": node},
            "bearings": {
                k: {
                    "load_N": b.load,
                    "force_N": b.force.tolist(),
                    "deflection_m": b.deflection.tolist(),
                    "stiffness_N_per_m": b.stiffness.tolist(),
                    "in_contact": b.in_contact,
                    "elements": b.elements,
                }
                for k, b in self.bearings.items()
            },
            "meshes": {
                k: {
                    "force_N": m.force,
                    "deflection_m": m.deflection,
                    "stiffness_N_per_m": m.stiffness,
                    "secant_N_per_m": m.secant,
                    "nominal_N_per_m": m.nominal,
                }
                for k, m in self.meshes.items()
            },
            "torques_N_m": dict(self.torques),
            "rigid_load": self.rigid_load.tolist(),
            "iterations": self.iterations,
            "load_steps": self.load_steps,
            "residual": self.residual,
        }

    def summary(self) -> list[str]:
        """Lines for a terminal summary."""
        peak, (body, node) = self.max_displacement()
        lines = [
            f"operating point: static equilibrium in {self.iterations} Newton iterations, "
            f"{self.load_steps} load step{'s' if self.load_steps > 1 else ''}, "
            f"relative residual {self.residual:.1e}; largest static deflection "
            f"{peak * 1e6:.3g} um at {body} node {node}"
        ]
        for k, t in self.torques.items():
            lines.append(f"  torque {k}: {t:.6g} N m")
        for k, b in self.bearings.items():
            kt = np.linalg.eigvalsh(0.5 * (b.stiffness + b.stiffness.T))
            contact = f", {b.in_contact} of {b.elements} elements in contact" if b.elements else ""
            lines.append(
                f"  bearing {k}: load {b.load:.6g} N, deflection "
                f"{np.linalg.norm(b.deflection) * 1e6:.4g} um, operating stiffness "
                f"{kt[-1]:.4g} / {kt[-2]:.4g} N/m (principal){contact}"
            )
        for k, m in self.meshes.items():
            lines.append(
                f"  mesh {k}: force {m.force:.6g} N, deflection {m.deflection * 1e6:.4g} um, "
                f"operating stiffness {m.stiffness:.4g} N/m ({m.stiffness / m.nominal:.3g} x "
                "nominal)"
            )
        if np.abs(self.rigid_load).max(initial=0.0) > 0:
            lines.append(
                "  load held by the constant-speed constraint (unbalanced torques): R^T f = "
                + ", ".join(f"{x:.3g}" for x in self.rigid_load)
            )
        return lines


# --------------------------------------------------------------------------- replay
def _replay(model: Any, replace: Callable[[str, dict[str, Any]], list[tuple[str, dict]]]) -> Any:
    from ..model import Model

    out = Model(input_body=model.input_body, unbalance_reference=model.unbalance_reference)
    for method, kwargs in model.calls:
        for name, kw in replace(method, kwargs):
            getattr(out, name)(**kw)
    return out


def _torque_force(model: Any, kw: dict[str, Any], value: float) -> tuple[str, dict[str, Any]]:
    axis = np.asarray(model.bodies[kw["body"]].axis, dtype=float)
    return "add_force", dict(
        name=kw["name"], body=kw["body"], node=kw["node"], moment=list(value * axis)
    )


_MESH_LAW_ARGS = ("load_law", "face_width", "load_forces", "load_stiffness")


def _base(model: Any) -> Any:
    """The linear part: no load-dependent bearings, nominal meshes, given torques as moments."""

    def replace(method: str, kw: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
        if method == "add_rolling_bearing":
            return []
        if method == "add_torque":
            t = model.torques[kw["name"]]["torque"]
            return [] if isinstance(t, str) else [_torque_force(model, kw, t)]
        if method == "add_gear_mesh":
            return [(method, {k: v for k, v in kw.items() if k not in _MESH_LAW_ARGS})]
        return [(method, kw)]

    return _replay(model, replace)


def _plane(axis: Any) -> np.ndarray:
    """The bearing plane's axes (3 x 2), right-handed about ``axis``: x and y for z."""
    a, b = transverse_basis(axis)
    return np.column_stack([-b, a])


# --------------------------------------------------------------------------- the solve
def operating_point(model: Any, speed: float) -> OperatingPoint:
    """Static equilibrium of ``model`` at input ``speed`` [rad/s] and its linearization (see
    the module). Raises :class:`~rheolin.errors.ModelError` naming the joint when no
    equilibrium is found."""
    base = _base(model)
    a = base.assemble(speed)
    system = a.system
    n = system.n
    K0 = sp.csr_array(system.K[0]) if 0 in system.K else sp.csr_array((n, n))
    f0 = np.real(np.asarray(system.f.get(0, np.zeros(n)), dtype=complex))
    M0 = sp.csr_array(system.M[0]) if 0 in system.M else sp.csr_array((n, n))

    def dofs(body: str, node: int) -> np.ndarray:
        return np.asarray(a.dofs(body, node))

    # bearings: B (2 x n) on the radial relative motion in the bearing plane
    bear: list[tuple[str, Any, sp.csr_array, np.ndarray, float]] = []
    for name, b in model.rolling.items():
        E = _plane(model.bodies[b["body"]].axis)
        rows = [np.repeat([0, 1], 3)]
        cols = [np.tile(dofs(b["body"], b["node"])[:3], 2)]
        vals = [E.T.ravel()]
        if b["other"][0] is not None:
            rows.append(np.repeat([0, 1], 3))
            cols.append(np.tile(dofs(*b["other"])[:3], 2))
            vals.append(-E.T.ravel())
        B = sp.csr_array(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(2, n)
        )
        bear.append((name, b["law"], B, E, b["damping"]))
    # meshes with a load law: their line-of-action vector over all DOFs
    mesh: list[tuple[str, Any, np.ndarray, float]] = []
    for name, g in model.meshes.items():
        if g.get("load_law") is None:
            continue
        term, w, _ = a.meshes[name]
        wv = np.zeros(n)
        np.add.at(wv, np.asarray(term.dofs), w)
        st = g["stiffness"]
        k0 = float(np.real(st.get(0, 0.0))) if isinstance(st, dict) else float(st)
        if not k0 > 0:
            raise ModelError(f"mesh {name!r}: a load law needs a positive mean stiffness")
        mesh.append((name, g["load_law"], wv, k0))
    # reaction torques
    reactions = [k for k, t in model.torques.items() if isinstance(t["torque"], str)]
    A = np.zeros((n, len(reactions)))
    for j, k in enumerate(reactions):
        t = model.torques[k]
        A[dofs(t["body"], t["node"])[3:], j] = np.asarray(model.bodies[t["body"]].axis, float)

    # eliminated DOFs: rigid links, then the free rigid-body motions
    T1 = sp.csr_array(
        system.constraint.transform()
        if system.constraint is not None
        else sp.identity(n, format="csr")
    )
    # the bearings' reference stiffness (their tangent at 1 um): the rigid-mode search, the
    # first guess and the regularization of singular steps
    Kjoints = sp.csr_array((n, n))
    for _, law, B, _, _ in bear:
        Kjoints = Kjoints + law.reference_stiffness() * sp.csr_array(B.T @ B)
    Kref = K0 + Kjoints
    reduced = PeriodicSystem(
        system.omega,
        M={0: sp.csc_array(T1.T @ M0 @ T1)},
        K={0: sp.csc_array(T1.T @ Kref @ T1)},
    )
    rigid = find_rigid_modes(reduced)
    if rigid is not None:
        T = sp.csr_array(T1 @ rigid.transform())
        R = T1 @ rigid.modes  # rigid modes over every DOF
    else:
        T, R = T1, np.zeros((n, 0))
    torques = {
        k: float(t["torque"]) for k, t in model.torques.items() if not isinstance(t["torque"], str)
    }
    if reactions:
        if R.shape[1] == 0:
            raise ModelError(
                f"torque {reactions[0]!r} = 'reaction': the model has no free rotation for it "
                "to balance (a torsional support holds the drive train); give its value [N m]"
            )
        G = R.T @ A
        x, *_ = np.linalg.lstsq(G, -(R.T @ f0), rcond=None)
        if np.linalg.matrix_rank(G, tol=1e-9 * max(np.abs(G).max(initial=0.0), 1e-300)) < len(
            reactions
        ):
            raise ModelError(
                f"reaction torques {reactions}: they do not act on independent free rotations "
                "of the drive train; give all but one of them a value [N m]"
            )
        torques.update({k: float(v) for k, v in zip(reactions, x, strict=True)})
        f0 = f0 + A @ x
    rigid_load = R.T @ f0 if R.size else np.zeros(0)
    if R.size:  # round-off of balanced torques is not a load
        floor = 1e-9 * (np.abs(R).T @ np.abs(f0))
        rigid_load = np.where(np.abs(rigid_load) > floor, rigid_load, 0.0)

    Tt = sp.csr_array(T.T)
    Kr = sp.csc_array(Tt @ K0 @ T)
    fr = Tt @ f0
    Br = [sp.csr_array(B @ T) for _, _, B, _, _ in bear]
    wr = [Tt @ wv for _, _, wv, _ in mesh]
    ww = []  # w w^T of each mesh, sparse
    for wj in wr:
        nz = np.flatnonzero(wj)
        ww.append(
            sp.csc_array(
                (np.outer(wj[nz], wj[nz]).ravel(), (np.repeat(nz, nz.size), np.tile(nz, nz.size))),
                shape=(T.shape[1], T.shape[1]),
            )
        )
    Kreg = sp.csc_array(Tt @ Kjoints @ T)
    for (_, _, _, k0), Wj in zip(mesh, ww, strict=True):
        Kreg = Kreg + k0 * Wj

    def evaluate(y: np.ndarray, lam: float, tangent: bool) -> tuple[np.ndarray, Any]:
        r = Kr @ y - lam * fr
        J = Kr.copy() if tangent else None
        for (_, law, _, _, _), Bj in zip(bear, Br, strict=True):
            F, Kt = law.force(Bj @ y)
            r = r - Bj.T @ F
            if tangent:
                J = J + sp.csc_array(Bj.T @ sp.csr_array(Kt) @ Bj)
        for (_, law, _, k0), wj, Wj in zip(mesh, wr, ww, strict=True):
            d = float(wj @ y)
            F, kt = law.force(d, k0)
            r = r + wj * (F - k0 * d)
            if tangent and np.isfinite(kt):
                J = J + (kt - k0) * Wj
        return r, J

    # residuals in consistent units (forces and moments): rows scaled by 1/sqrt(K_ii) of the
    # reference stiffness (an energy-like norm for the line search and the convergence test)
    diag = np.abs((Kr + Kreg).diagonal())
    weight = 1.0 / np.sqrt(np.where(diag > 0, diag, max(diag.max(initial=0.0), 1.0)))
    scale = max(float(np.linalg.norm(weight * fr)), 1e-300)
    guess = np.zeros(T.shape[1])
    try:  # a first guess: the linear problem with the joints' reference stiffness
        with np.errstate(all="ignore"):
            g = spla.splu(sp.csc_array(Kr + Kreg)).solve(fr)
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
        ok, y_new, its, res = _newton(evaluate, start, target, scale, Kreg, weight)
        iterations += its
        if ok:
            y, lam, steps = y_new, target, steps + 1
            step = min(2 * step, 1.0)
            continue
        last = (target, res)
        step /= 2
        if step < MIN_STEP:
            raise ModelError(_diagnose(model, bear, T @ y_new, lam, last))
    u = np.asarray(T @ y)
    r_end, _ = evaluate(y, 1.0, False)
    residual = float(np.linalg.norm(weight * r_end)) / scale

    _plausible(model, bear, u, a)
    # joint states and the linearized model
    bstates: dict[str, BearingState] = {}
    for name, law, B, E, _ in bear:
        d2 = B @ u
        F2, Kt2 = law.force(d2)
        bstates[name] = BearingState(
            deflection=E @ d2,
            force=-(E @ F2),
            stiffness=E @ Kt2 @ E.T,
            in_contact=law.in_contact(d2),
            elements=int(law.elements) if law.law == "elements" else 0,
        )
    mstates: dict[str, MeshState] = {}
    for name, law, wv, k0 in mesh:
        d = float(wv @ u)
        F, kt = law.force(d, k0)
        if F < 0:
            raise ModelError(
                f"mesh {name!r} is loaded on its other flank (mean force {F:.4g} N): set its "
                "`side` to the loaded flank, or reverse the torques"
            )
        if not (np.isfinite(kt) and kt > 0):
            raise ModelError(
                f"mesh {name!r} carries no load ({F:.3g} N): its load law gives no stiffness"
            )
        ksec = F / d if d else law.k(0.0, k0)[0]
        mstates[name] = MeshState(force=F, deflection=d, secant=ksec, stiffness=kt, nominal=k0)
    lin = _linearized(model, bstates, bear, mstates, torques)
    return OperatingPoint(
        speed=float(speed),
        displacement=u,
        dof_labels=a.dof_labels,
        node_index=a.node_index,
        bearings=bstates,
        meshes=mstates,
        torques=torques,
        rigid_load=np.asarray(rigid_load, dtype=float),
        iterations=iterations,
        load_steps=steps,
        residual=residual,
        model=lin,
    )


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


def _diagnose(model: Any, bear: list, u: np.ndarray, lam: float, last: tuple[float, float]) -> str:
    """The message of a failed equilibrium, naming the joint most likely at fault."""
    target, res = last
    head = (
        f"static equilibrium not found: Newton stalled at {target:.1%} of the static load "
        f"(solved up to {lam:.1%}; residual {res:.3g} N)"
    )
    worst, why = None, ""
    for name, law, B, _, _ in bear:
        d = B @ u
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


#: A static deflection beyond this fraction of the model's size is not a small-deflection
#: operating point (the linear theory of every joint and body is void there).
MAX_DEFLECTION = 1e-2


def _plausible(model: Any, bear: list, u: np.ndarray, a: Any) -> None:
    """Refuse an equilibrium the laws cannot vouch for: a table bearing beyond its table, or
    a deflection that is not small against the model (a joint that cannot carry its load lets
    the linear rest of the model find a far-away balance)."""
    for name, law, B, _, _ in bear:
        if law.law == "table":
            r = float(np.hypot(*(B @ u)))
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
        worst = max(bear, key=lambda b: float(np.hypot(*(b[2] @ u))), default=None)
        blame = (
            f"; bearing {worst[0]!r} deflects {float(np.hypot(*(worst[2] @ u))) * 1e3:.4g} mm"
            if worst is not None
            else ""
        )
        raise ModelError(
            f"static equilibrium at an implausible deflection: {peak * 1e3:.4g} mm at "
            f"{where[0]} node {where[1]}, {peak / size:.3g} of the model's size{blame}: a "
            "joint cannot carry its load (a small-deflection operating point needs below "
            f"{MAX_DEFLECTION:.0%})"
        )


def _linearized(
    model: Any,
    bstates: dict[str, BearingState],
    bear: list,
    mstates: dict[str, MeshState],
    torques: dict[str, float],
) -> Any:
    damping = {name: c * (E @ E.T) for name, _, _, E, c in bear}

    def replace(method: str, kw: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
        if method == "add_rolling_bearing":
            st = bstates[kw["name"]]
            b = model.rolling[kw["name"]]
            preload = st.force - st.stiffness @ st.deflection
            other_body, other_node = b["other"]
            return [
                (
                    "add_bearing",
                    dict(
                        name=kw["name"],
                        body=b["body"],
                        node=b["node"],
                        stiffness=st.stiffness,
                        damping=damping[kw["name"]],
                        components=list(COMPONENTS[:3]),
                        other_body=other_body,
                        other_node=other_node,
                        preload=preload,
                    ),
                )
            ]
        if method == "add_torque":
            return [_torque_force(model, kw, torques[kw["name"]])]
        if method == "add_gear_mesh":
            kw = {k: v for k, v in kw.items() if k not in _MESH_LAW_ARGS}
            ms = mstates.get(kw["name"])
            if ms is None:
                return [(method, kw)]
            g = model.meshes[kw["name"]]
            ratio = ms.stiffness / ms.nominal
            te = dict(g["transmission_error"] or {})
            te[0] = te.get(0, 0.0) + (ms.deflection - ms.force / ms.stiffness)
            # the stiffness function scaled as it was given (a mean, a Fourier series, or the
            # rectangular wave's two levels): the model file can still say it
            given = kw.get("stiffness")
            if given is not None:
                kw["stiffness"] = (
                    {j: v * ratio for j, v in given.items()}
                    if isinstance(given, dict)
                    else given * ratio
                )
            for key in ("single_stiffness", "double_stiffness"):
                if kw.get(key) is not None:
                    kw[key] = kw[key] * ratio
            kw["transmission_error"] = te
            return [(method, kw)]
        return [(method, kw)]

    return _replay(model, replace)


# --------------------------------------------------------------------------- templates
class _PerSpeedTemplate:
    """A preloaded model whose static stiffness changes with the speed: linearized at each
    speed (the operating point is cached per speed on the model)."""

    time_invariant = False

    def __init__(self, model: Any) -> None:
        self.model = model
        self.plan = model.speed_plan()

    def assemble(self, speed: float) -> Any:
        return self.model.assemble(speed)


def speed_independent(model: Any) -> bool:
    """True when the static problem of a preloaded model does not depend on the speed (no
    speed tables, no speed-dependent mean stiffness or static load): one operating point
    serves every speed."""
    from ..template import SpeedTemplate

    base = SpeedTemplate(_base(model))
    K = base._K.patterns.get(0)
    still = not base.tables and (K is None or not np.any(K[2][1:]))
    f = base.load_polynomials().get(0)
    return bool(still and (f is None or not np.any(f[1:])))


def linearized(model: Any) -> Any:
    """The model linearized at its operating point, for analyses over speed that edit or
    inspect a model's joints (the critical-speed map); a model that is not preloaded is
    returned as it is. Refused when the operating point changes with the speed."""
    if not model.preloaded:
        return model
    if not speed_independent(model):
        raise ModelError(
            "this preloaded model's operating point changes with the speed (speed-dependent "
            "stiffness or static load): use the Campbell diagram (rheolin campbell), which "
            "linearizes at every speed"
        )
    return model.operating_point(1.0).model


def preloaded_template(model: Any) -> Any:
    """``model.speed_template()`` of a preloaded model: one linearization when its static
    problem does not depend on the speed, else one per speed."""
    if speed_independent(model):
        return model.operating_point(1.0).model.speed_template()
    return _PerSpeedTemplate(model)
