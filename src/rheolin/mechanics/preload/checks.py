"""What the static equilibrium refuses and reports, in the user's terms: a load nothing carries
(named by joint or body, in N or N m), an equilibrium the laws cannot vouch for, a rolling
bearing the load leaves open, and the load the constant-speed assumption takes.

>>> import numpy as np
>>> load_in_units(np.array([0.0, 2.0, 0.0, 0.0, 0.0, 0.0]), np.array([0, -98.1, 0, 0, 0, 0]),
...               [("r", 0, c) for c in ("ux", "uy", "uz", "phix", "phiy", "phiz")])
(-98.1, 'N')
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...errors import ModelError
from ...system.motions import FreeMotion
from ...system.rigid_modes import free_body_message
from ..assembly import Assembled
from ..items import ModelData

__all__ = [
    "MAX_DEFLECTION",
    "held_loads",
    "load_in_units",
    "plausible",
    "stalled",
    "unbounded",
    "unheld_with_load",
]

#: A static deflection beyond this fraction of the model's size is not a small-deflection
#: operating point (the linear theory of every joint and body is void there).
MAX_DEFLECTION = 1e-2

_TRANSLATIONS = ("ux", "uy", "uz")


def load_in_units(
    v: np.ndarray, f: np.ndarray, labels: list[tuple[str, int, str]]
) -> tuple[float, str]:
    """The generalized load ``v^T f`` of a motion ``v`` scaled so that its largest translation
    is 1 m (a force, N), or, without translation, its largest rotation 1 rad (a moment, N m)."""
    v = np.asarray(v, float)
    trans = np.array([lab[2] in _TRANSLATIONS for lab in labels[: v.size]])
    top = float(np.abs(v[trans]).max(initial=0.0))
    if top > 1e-9 * float(np.abs(v).max(initial=0.0)):
        return float(v @ f) / top, "N"
    rot = float(np.abs(v[~trans]).max(initial=0.0))
    return (float(v @ f) / rot if rot > 0 else 0.0), "N m"


def model_size(model: ModelData) -> float:
    """The largest extent of the model's nodes [m] (0 for a single node)."""
    positions = np.concatenate([b.positions for b in model.bodies.values()])
    return float(np.ptp(positions, axis=0).max()) if len(positions) > 1 else 0.0


def unheld_with_load(
    free: list[FreeMotion], f0: np.ndarray, labels: list[tuple[str, int, str]]
) -> None:
    """Refuse the static problem when a motion nothing holds carries load: no equilibrium."""
    loaded = []
    for m in free:
        if m.vector is None:
            continue
        value, unit = load_in_units(m.vector, f0, labels)
        if abs(value) > 1e-9 * max(float(np.abs(f0).max(initial=0.0)), 1e-300):
            loaded.append((m, value, unit))
    if loaded:
        m, value, unit = max(loaded, key=lambda x: abs(x[1]))
        raise ModelError(
            free_body_message(
                [x[0] for x in loaded],
                why=f", and the static load pushes it ({abs(value):.4g} {unit}: no static "
                "equilibrium exists)",
            )
        )


def unbounded(
    bearings: list[Any],
    meshes: list[Any],
    y: np.ndarray,
    d: np.ndarray,
    f: np.ndarray,
    limit: float,
) -> str:
    """The message of a search that found no equilibrium along ``d``: the joint that moves
    most along it, the static load it would have to carry [N] and what its law gives."""
    best, move, kind = None, 0.0, ""
    for j in bearings:
        m = float(np.linalg.norm(j.B @ d))
        if m > move:
            best, move, kind = j, m, "bearing"
    for g in meshes:
        m = abs(float(g.w @ d))
        if m > move:
            best, move, kind = g, m, "mesh"
    head = (
        f"static equilibrium does not exist: the static load is not carried within "
        f"{limit * 1e3:.4g} mm of deflection"
    )
    if best is None or move == 0.0:
        return head + "; no bearing or mesh acts along the direction it pushes"
    load = abs(float(d @ f)) / move  # the load along that joint's own deflection [N]
    far = y + d * (limit / move)
    if kind == "bearing":
        F, _ = best.law.force(best.B @ far)
        extra = ""
        if best.law.law == "table":
            extra = (
                f" (its table ends at {best.law.deflection[-1] * 1e6:.4g} um, "
                f"{best.law.force_table[-1]:.4g} N)"
            )
        return (
            f"{head}: bearing {best.name!r} would carry {load:.4g} N, but its law gives "
            f"{np.linalg.norm(F):.4g} N at {limit * 1e3:.4g} mm{extra}; stiffen the bearing "
            "or check the load"
        )
    Fm, _ = best.law.force(float(best.w @ far), best.nominal)
    return (
        f"{head}: mesh {best.name!r} would carry {load:.4g} N, but its load law gives "
        f"{abs(Fm):.4g} N at {limit * 1e3:.4g} mm; check its load law"
    )


def stalled(
    bearings: list[Any],
    meshes: list[Any],
    u: np.ndarray,
    force: np.ndarray,
    labels: list[tuple[str, int, str]],
) -> str:
    """The message of an equilibrium that was not found (no convergence): the out-of-balance
    force [N] (or moment [N m]) and where, and the joints' states there."""
    trans = np.array([lab[2] in _TRANSLATIONS for lab in labels[: force.size]])
    parts = []
    for mask, unit in ((trans, "N"), (~trans, "N m")):
        if mask.any():
            i = int(np.flatnonzero(mask)[np.argmax(np.abs(force[mask]))])
            b, node, c = labels[i]
            parts.append(f"{abs(force[i]):.3g} {unit} ({b} node {node} {c})")
    text = "static equilibrium not found (Newton did not converge): out-of-balance " + " and ".join(
        parts
    )
    states = []
    for j in bearings:
        d = j.B @ u
        states.append(
            f"bearing {j.name!r}: {j.law.in_contact(d)} in contact, radial deflection "
            f"{np.hypot(*d) * 1e6:.3g} um"
        )
    for g in meshes:
        states.append(f"mesh {g.name!r}: deflection {float(g.w @ u) * 1e6:.3g} um")
    return text + ("; " + "; ".join(states) if states else "")


def plausible(model: ModelData, bearings: list[Any], u: np.ndarray, a: Assembled) -> None:
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
    size = model_size(model)
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


def held_loads(
    model: ModelData,
    R: np.ndarray,
    f0: np.ndarray,
    labels: list[tuple[str, int, str]],
    node_index: dict[tuple[str, int], int],
    torques: dict[str, float],
) -> list[dict[str, Any]]:
    """The mean load on each held rigid-body mode (the drive train's rotation: a net torque;
    its axial motion: a net thrust), in N m or N at the body the mode turns or moves most,
    with the torques given or balanced: what the constant-speed assumption (the drive)
    takes."""
    out: list[dict[str, Any]] = []
    for k in range(R.shape[1]):
        r = R[:, k]
        total = float(r @ f0)
        if abs(total) <= 1e-9 * float(np.abs(r) @ np.abs(f0)):  # balanced, to round-off
            continue
        best, amount, unit, what = "", 0.0, "", ""
        for b in model.bodies.values():
            i = node_index[(b.name, 0)]
            e = np.asarray(b.axis, float)
            spin = float(r[6 * i + 3 : 6 * i + 6] @ e)
            axial = float(r[6 * i : 6 * i + 3] @ e)
            if abs(spin) > abs(amount):
                best, amount, unit, what = b.name, spin, "N m", "rotation about its axis"
            if abs(axial) > abs(amount) and abs(axial) > 1e-3 * abs(spin):
                best, amount, unit, what = b.name, axial, "N", "axial motion"
        if not best:
            continue
        acting = {name: value for name, value in torques.items() if value}
        out.append(
            dict(
                body=best,
                motion=what,
                load=total / amount,
                unit=unit,
                torques=acting,
            )
        )
    return out
