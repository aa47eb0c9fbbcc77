"""Stability at standstill: the time-invariant system frozen where the machine stands.

At ``W = 0`` nothing turns: the gear meshes stay at the tooth positions of ``t = 0`` and the
shafts at their angles there, so the coefficients are constant, ``M(0), D(0), K(0)`` (the
periodic coefficients summed at ``t = 0``), and the exponents are the eigenvalues of that
time-invariant system, exactly. A Floquet analysis at a tiny speed instead would see a
degenerate lattice (every harmonic copy of an exponent at the same place) and decide it
only at great cost.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..floquet import FloquetResult, floquet
from ..system.periodic import PeriodicSystem

__all__ = ["STANDSTILL", "STANDSTILL_NOTE", "frozen_system", "standstill_verdict"]

#: The speed [rad/s] a standstill point is assembled at (a Campbell diagram's modes, the
#: frozen system of a stability map): the speed terms are 1e-9 of their value at 1 rad/s.
STANDSTILL = 1e-9

#: What a standstill verdict says it did (``FloquetResult.info["note"]``).
STANDSTILL_NOTE = (
    "standstill: the eigenvalues of the time-invariant system frozen at t = 0 "
    "(M(0), D(0), K(0): the gear and shaft positions of the model), exact at W = 0"
)


def _at_zero(table: dict[int, Any]) -> Any:
    """``sum_k X_k``: a coefficient's value at ``t = 0`` (real; sparse stays sparse)."""
    total: Any = None
    for x in table.values():
        total = x if total is None else total + x
    if total is None:
        return None
    return total.real if np.iscomplexobj(total) else total


def frozen_system(system: PeriodicSystem) -> PeriodicSystem:
    """The time-invariant system of ``system``'s coefficients at ``t = 0``.

    Its constraints (rigid links) and the bodies behind its DOFs carry over, so that the
    analyses eliminate and hold the same motions.

    >>> import numpy as np
    >>> s = PeriodicSystem(2.0, M={0: np.eye(1)}, K={0: np.eye(1), 1: 0.25 * np.eye(1)})
    >>> f = frozen_system(s)
    >>> f.time_invariant, f.K[0].tolist()
    (True, [[1.5]])
    """
    parts = {name: _at_zero(getattr(system, name)) for name in ("M", "D", "K")}
    out = PeriodicSystem(
        system.omega,
        M=None if parts["M"] is None else {0: parts["M"]},
        D=None if parts["D"] is None else {0: parts["D"]},
        K=None if parts["K"] is None else {0: parts["K"]},
        constraint=system.constraint,
    )
    out.whirl_pairs = system.whirl_pairs
    out.motions = system.motions
    return out


def standstill_verdict(model: Any, speed: float, **options: Any) -> FloquetResult:
    """The stability verdict at standstill: :func:`rheolin.floquet` of the model assembled at
    ``speed`` (a tiny speed > 0: the speed terms, gyroscopic and centrifugal, are that
    fraction of their value at 1 rad/s) and frozen at ``t = 0`` (:func:`frozen_system`);
    ``info["note"]`` says so. ``options`` go to :func:`rheolin.floquet` (``memory_budget``)."""
    a = model.assemble(float(speed))
    res = floquet(frozen_system(a.system), method="lattice", **options)
    note = res.info.get("note")
    res.info["note"] = f"{STANDSTILL_NOTE}; {note}" if note else STANDSTILL_NOTE
    res.info["standstill"] = True
    return res
