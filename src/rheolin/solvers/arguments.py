"""What ``rl.solve`` checks of its arguments before any work: each option a user types refused
by name, a harmonic set refused from its count when its size alone is past the memory
budget (before it is built), and a set that leaves out every load harmonic.

>>> import numpy as np, rheolin as rl
>>> s = rl.PeriodicSystem(1.0, M={0: np.eye(1)}, K={0: np.eye(1)}, f={1: np.ones(1)})
>>> check_loads(s, rl.HarmonicSet([0, 2]), warn=True)  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
rheolin.errors.ModelError: `harmonics`: the set leaves out every load harmonic (-1, 1): ...
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..budget import MemoryBudgetError, solve_budget
from ..errors import ModelError
from ..harmonics.sets import HarmonicSet, TruncationWarning
from ..linalg.memory import SolveMemory
from ..linalg.memory import check as check_memory
from ..system.periodic import PeriodicSystem

__all__ = ["check_arguments", "check_loads", "check_size"]


def check_arguments(
    maxiter: Any, method: Any, budget: Any, backend: Any, sparse_backend: Any
) -> None:
    """The options a user types, each refused by name (before any conversion fails)."""
    if maxiter is not None:
        ok = isinstance(maxiter, int | np.integer) and not isinstance(maxiter, bool)
        if not ok or int(maxiter) < 1:
            raise ValueError(f"`maxiter` must be a positive integer, got {maxiter!r:.80}")
    if not isinstance(method, str):
        raise ValueError(f"`method` must be a method name (a str), got {method!r:.80}")
    for name, value in (("backend", backend), ("sparse_backend", sparse_backend)):
        if not isinstance(value, str):
            raise ValueError(f"`{name}` must be a backend name (a str), got {value!r:.80}")
    if budget is not None:
        try:
            solve_budget(budget)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"`memory_budget`: {exc}") from None


def check_size(system: PeriodicSystem, harmonics: Any, budget: str | int | None) -> None:
    """Refuse a harmonic set whose size alone takes the solve past its memory budget (the
    operator's estimate without the factors, :class:`~rheolin.linalg.memory.SolveMemory`),
    from its count (an int ``N``: ``N + 1`` harmonics ``n >= 0``), before it is built."""
    if isinstance(harmonics, int | np.integer) and not isinstance(harmonics, bool):
        if int(harmonics) < 0:
            raise ValueError(f"`harmonics` must be >= 0, got {harmonics!r}")
        half = int(harmonics) + 1
    else:
        try:
            half = len(harmonics) // 2 + 1
        except TypeError:  # an iterator: built and checked by the operator's estimate
            return
    touched = np.zeros(system.n, bool)  # the support of the time variation
    for name in ("M", "D", "K"):
        for k, X in getattr(system, name).items():
            if k:
                touched[np.flatnonzero(np.abs(X).sum(axis=1))] = True
    memory = SolveMemory(system.n, half, int(touched.sum()))
    try:
        check_memory(memory, solve_budget(budget))
    except MemoryBudgetError as exc:
        raise MemoryBudgetError(f"`harmonics`: {exc}") from None


def check_loads(system: PeriodicSystem, hset: HarmonicSet, warn: bool) -> None:
    """Refuse a harmonic set that leaves out every load harmonic (its answer would be q = 0
    whatever the model), and warn (``warn``: a set given as numbers; a closure says what its
    cut-off leaves out itself) when it leaves out some."""
    loads = [int(k) for k in system.load_harmonics]
    if not loads:
        return
    have = set(int(k) for k in hset.indices)
    missing = [k for k in loads if k not in have]
    if len(missing) == len(loads):
        raise ModelError(
            f"`harmonics`: the set leaves out every load harmonic ({short(loads)}): the "
            "response would be zero whatever the model; include them (e.g. "
            "HarmonicSet.closure(system, order))"
        )
    if missing and warn:
        warnings.warn(
            f"the harmonic set leaves out {len(missing)} of {len(loads)} load harmonics "
            f"({short(missing)}): their response is not computed",
            TruncationWarning,
            stacklevel=3,
        )


def short(values: list[int], head: int = 6) -> str:
    shown = ", ".join(str(v) for v in values[:head])
    return shown + (", ..." if len(values) > head else "")
