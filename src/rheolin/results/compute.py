"""One operating point of a model: assemble, choose the harmonic set, solve.

Kept apart from the CLI so that tests and scripts get exactly what ``rheolin run`` computes.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from typing import Any

from ..harmonics.sets import HarmonicSet, TruncationWarning
from ..mechanics.assembly import Assembled
from ..mechanics.model import Model
from ..mechanics.template import SpeedTemplate
from ..solvers import solve
from ..solvers.solution import Solution

__all__ = ["OperatingPoint", "harmonic_set", "solve_point"]


@dataclass
class OperatingPoint:
    """The assembled model at one speed, its harmonic set, the solution and timings."""

    assembled: Assembled
    harmonics: HarmonicSet
    solution: Solution
    seconds: float
    settings: dict[str, Any] = field(default_factory=dict)
    positions: dict[tuple[str, int], Any] = field(default_factory=dict)


def harmonic_set(a: Assembled, order: int = 2, max_order: float | None = None) -> HarmonicSet:
    """Closure harmonic set: ``order`` steps of the model's generators from the loads.

    ``max_order`` caps the frequency at ``max_order`` times the input speed (None: no cap).
    The cap is in orders, so the same harmonic indices are used at every speed of a sweep.

    >>> from rheolin.io import load_model
    >>> from rheolin.data import example_path
    >>> a = load_model(example_path("rotor")).assemble(100.0)
    >>> len(harmonic_set(a, order=2)) > 0
    True
    """
    cap = None if max_order is None else int(max_order / float(a.base_ratio))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        hset = HarmonicSet.closure(a.system, order=order, max_harmonic=cap, generators=a.generators)
    for w in caught:
        if not issubclass(w.category, TruncationWarning):
            warnings.warn(w.message, w.category, stacklevel=2)
            continue
        base = float(a.base_ratio)
        loads = sorted(k for k in a.system.load_harmonics if k >= 0)
        out = [k for k in loads if cap is not None and k > cap]
        orders = [f"{k * base:.4g}" for k in out]
        shown = orders if len(orders) <= 6 else [*orders[:5], "...", orders[-1]]
        warnings.warn(
            f"max_order={max_order:g} leaves out {len(out)} of {len(loads)} load harmonics "
            f"(orders {', '.join(shown)} of the input speed): their response is not computed; "
            f"max_order >= {out[-1] * base:.4g} keeps them",
            TruncationWarning,
            stacklevel=2,
        )
    return hset


def _mechanism(model: Model, a: Any, res: Any) -> str:
    """The label of an unstable lattice result's mechanism. Bodies written in their own
    frames (a large model, docs/stability.md section 8) turn an asymmetric shaft's band into a
    time-invariant instability there: named so."""
    from ..stability.mechanism import ASYMMETRY, CIRCULATORY, ROTATING_DAMPING, identify

    mech = identify(model, a, res)
    frames = (res.info.get("band") or {}).get("frames") or []
    if frames and mech.category in (CIRCULATORY, ROTATING_DAMPING):
        return f"{ASYMMETRY} (time-invariant in the frame of {', '.join(frames)})"
    return str(mech.label)


def solve_point(
    model: Model,
    speed: float,
    *,
    method: str = "auto",
    order: int = 2,
    max_order: float | None = None,
    rtol: float = 1e-10,
    stability: bool | None = None,
    callback: Any = None,
    template: SpeedTemplate | None = None,
    x0: Any = None,
    backend: str = "auto",
    continuation: Any = None,
) -> OperatingPoint:
    """Assemble ``model`` at input ``speed`` [rad/s] and solve for the periodic steady state.

    ``template`` (``model.speed_template()``) skips re-reading the model at every speed of a
    sweep; ``x0`` (e.g. the solution at the previous speed) starts the iterative solver;
    ``backend`` and ``continuation`` (a :class:`~rheolin.floquet.Continuation` over the
    speeds of a sweep) are passed to :func:`rheolin.solve`.

    ``stability=None`` checks Floquet stability whenever it fits the memory budget (as
    :func:`rheolin.solve`).

    >>> from rheolin.io import load_model
    >>> from rheolin.data import example_path
    >>> p = solve_point(load_model(example_path("rotor")), 150.0, stability=False)
    >>> p.solution.success, p.solution.stable
    (True, None)
    """
    t0 = time.perf_counter()
    a = (template or model.speed_template()).assemble(speed)
    hset = harmonic_set(a, order, max_order)
    sol = solve(
        a.system,
        hset,
        method=method,
        rtol=rtol,
        callback=callback,
        stability=stability,
        x0=x0,
        backend=backend,
        continuation=continuation,
    )
    dominant = sol.info.get("rigid_dominant_dofs")
    if dominant:  # name the free motions by their body and component: "rotor uz, rotor phiz"
        names = ", ".join(f"{b} {c}" for b, _, c in (a.dof_labels[j] for j in dominant))
        sol.message = sol.message.replace(
            "(free motion with mass", f"({names}: free motion with mass", 1
        )
    res = sol.floquet
    if res is not None and not res.stable and res.method == "lattice":
        sol.info["stability_mechanism"] = _mechanism(model, a, res)
    settings = dict(method=method, order=order, max_order=max_order, rtol=rtol)
    positions = {(b.name, i): x for b in model.bodies.values() for i, x in enumerate(b.positions)}
    return OperatingPoint(a, hset, sol, time.perf_counter() - t0, settings, positions)
