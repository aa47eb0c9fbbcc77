"""Checks before any work: what the model file implies, estimated against the memory budget.

:func:`rheolin.io.read_model` checks each field (types, units, ranges, references). What only
the whole model shows is checked here, once, by ``rheolin validate`` and by every command
before it computes anything:

* the model assembles at the operating speed (gear geometry, bearing frames, condensed
  matrices; each error names its field);
* the time-averaged mass matrix has no negative direction (positive semidefinite);
* no body is free in a direction that only a support can hold (a shaft without lateral
  bearings has no steady state; a drive train's rotation and axial position are held);
* the harmonic set that ``[harmonics]`` (or ``--harmonics``/``--max-order``) asks for, times
  the degrees of freedom, fits the memory budget: the closure is grown with a size limit and
  refused with the estimate (``MemoryBudgetError``) before it can exhaust the machine.

>>> from rheolin.io import read_model
>>> from rheolin.data import example_path
>>> info = preflight(read_model(example_path("rotor")), None)
>>> info.n_dof, info.harmonic_count
(18, 11)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..budget import MemoryBudgetError, format_bytes, solve_budget
from ..errors import ModelError
from ..linalg.memory import MIN_RESTART, SolveMemory

__all__ = ["VECTORS_PER_HARMONIC", "Preflight", "check_free_bodies", "preflight"]

#: Complex vectors per harmonic and DOF that any solve holds at least (load, solution,
#: residual and a few Krylov vectors): the floor of the memory estimate of a harmonic set.
VECTORS_PER_HARMONIC = 8

#: Speed [rad/s] at which a model without an operating speed is assembled for the checks.
CHECK_SPEED = 100.0


@dataclass(frozen=True)
class Preflight:
    """What the checks found: degrees of freedom, harmonics, the working-memory floor."""

    n_dof: int
    harmonic_count: int
    estimate: int

    def describe(self) -> str:
        """``"18 DOF x 10 harmonics (at least 23 kB to solve)"``."""
        if not self.harmonic_count:
            return f"{self.n_dof} DOF, no load"
        return (
            f"{self.n_dof} DOF x {self.harmonic_count} harmonics (at least "
            f"{format_bytes(self.estimate)} to solve)"
        )


def preflight(
    lm: Any,
    speeds: Sequence[float] | np.ndarray | None,
    *,
    order: int | None = None,
    max_order: float | None = None,
    budget: int | None = None,
    needs_load: bool = True,
    free_bodies: bool | None = None,
) -> Preflight:
    """Check a loaded model (:class:`~rheolin.io.LoadedModel`) at the first of ``speeds``
    (default: the file's ``model.speed``) with the harmonic settings ``order``/``max_order``
    (default: the file's); raise :class:`~rheolin.ModelError` or
    :class:`~rheolin.budget.MemoryBudgetError` naming the field. ``needs_load=False`` (a
    Campbell diagram) accepts a model without loads; ``free_bodies`` (default:
    ``needs_load``) refuses a body that only a support could hold and nothing holds
    (:func:`check_free_bodies`: a steady state needs it held)."""
    from ..harmonics.sets import HarmonicSet

    h = lm.spec.harmonics
    order = h.order if order is None else order
    max_order = h.max_order if max_order is None else max_order
    speed = float(speeds[0]) if speeds is not None and len(speeds) else lm.spec.model.speed
    a = lm.model.assemble(float(speed) if speed else CHECK_SPEED)
    system = a.system
    _check_mass(system)
    if needs_load if free_bodies is None else free_bodies:  # a Campbell diagram needs not
        check_free_bodies(system)
    n = int(system.n)
    per_harmonic = _per_harmonic(system)
    limit = solve_budget() if budget is None else int(budget)
    max_size = max(limit // per_harmonic, 1)
    if not system.load_harmonics:
        if not needs_load:
            return Preflight(n, 0, 0)
        at = f"{speed:.6g} rad/s" if speed else "the check speed"
        raise ModelError(
            f"loads: the model has no load at {at} (no unbalance, force, gravity or "
            "transmission error; unbalance loads vanish with the speed squared): there is "
            "no steady-state response to compute; add a load (`rheolin campbell` needs none)"
        )
    cap = None if max_order is None else int(max_order / float(a.base_ratio))
    where = "--harmonics / [harmonics].order" if order != h.order else "harmonics.order"
    try:
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the run says it (TruncationWarning)
            hset = HarmonicSet.closure(
                system, order=order, max_harmonic=cap, generators=a.generators, max_size=max_size
            )
    except MemoryBudgetError:
        raise MemoryBudgetError(
            f"{where}: order {order}"
            + ("" if max_order is None else f" with max_order {max_order:g}")
            + f" grows the harmonic set past {max_size:,} harmonics, the most that fit the "
            f"memory budget of {format_bytes(limit)} with {n} DOF (a solve holds at least "
            f"{format_bytes(per_harmonic)} per harmonic: {VECTORS_PER_HARMONIC} complex "
            f"vectors and a GMRES basis of its shortest restart, {MIN_RESTART}); lower "
            "`order` or set `max_order` "
            "(or raise RHEOLIN_SOLVE_MEMORY)"
        ) from None
    except ValueError as exc:
        raise ModelError(f"harmonics: {exc}") from None
    return Preflight(n, len(hset), len(hset) * per_harmonic)


def _per_harmonic(system: Any) -> int:
    """Bytes a solve holds per harmonic of the two-sided set, before any factor: at least
    :data:`VECTORS_PER_HARMONIC` complex vectors, or the operator's own estimate of its
    vectors and GMRES basis with the shortest restart it is given to fit a budget
    (:class:`~rheolin.linalg.memory.SolveMemory`, per harmonic ``n >= 0``, two of which make
    about one of each sign)."""

    touched = np.zeros(system.n, bool)  # the support of the time variation
    for name in ("M", "D", "K"):
        for k, X in getattr(system, name).items():
            if k:
                touched[np.flatnonzero(np.abs(X).sum(axis=1))] = True
    operator = SolveMemory(system.n, 2, int(touched.sum()), restart=MIN_RESTART).total // 2
    return max(VECTORS_PER_HARMONIC * 16 * system.n, operator)


def check_free_bodies(system: Any) -> None:
    """No body has a rigid motion that nothing holds but the drive's spin and axial position
    (:func:`~rheolin.system.rigid_modes.held_rigid_modes`; the search costs one dense
    eigendecomposition, so models above its dense size are checked by the solve itself)."""
    from ..system.rigid_modes import DENSE_LIMIT, held_rigid_modes

    if system.constraint is not None:
        system = system.constraint.reduce(system)
    if system.n <= DENSE_LIMIT:
        held_rigid_modes(system)


def _check_mass(system: Any) -> None:
    """The time-averaged mass matrix is positive semidefinite (no negative kinetic energy).

    Checked on its diagonal and, for systems small enough, on its spectrum; condensed bodies
    are checked on their own when loaded (:mod:`rheolin.mechanics.condensed`).
    """
    M = system.M.get(0) if hasattr(system, "M") else None
    if M is None:
        return
    diag = np.real(np.asarray(M.diagonal()))
    scale = float(np.abs(diag).max(initial=0.0))
    if np.any(diag < -1e-12 * scale):
        i = int(np.argmin(diag))
        raise ModelError(
            f"mass: the assembled mass matrix has a negative diagonal entry {diag[i]:.4g} at "
            f"DOF {i}; masses and inertias must be >= 0"
        )
    if system.n <= 600:
        dense = M.toarray() if hasattr(M, "toarray") else np.asarray(M)
        low = float(np.linalg.eigvalsh(0.5 * (dense + dense.conj().T)).min())
        if low < -1e-9 * max(scale, 1e-300) * system.n:
            raise ModelError(
                f"mass: the assembled mass matrix has a negative eigenvalue {low:.4g} "
                "(negative kinetic energy); masses and inertias must be positive semidefinite"
            )
