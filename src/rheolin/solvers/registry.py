"""Registry of steady-state methods: each takes the operator and options, returns an outcome."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..harmonics.balance import HarmonicBalance

__all__ = ["METHODS", "Options", "SolverOutcome", "register"]


@dataclass
class Options:
    """Keyword options shared by every method."""

    rtol: float = 1e-10
    maxiter: int | None = None
    callback: Callable[[int, float], None] | None = None
    extra: dict = field(default_factory=dict)
    #: Initial guess: the half ``n >= 0`` of the coefficients (None: start from zero).
    x0: np.ndarray | None = None


@dataclass
class SolverOutcome:
    """What a method returns: the half ``n >= 0`` of the coefficients and diagnostics."""

    Q: np.ndarray
    converged: bool
    status: int
    message: str
    method: str
    iterations: int = 0
    history: list[float] = field(default_factory=list)
    info: dict = field(default_factory=dict)


Method = Callable[[HarmonicBalance, Options], SolverOutcome]

#: Methods by name; ``solve(..., method=name)`` dispatches here.
METHODS: dict[str, Method] = {}

#: Methods that solve the truncated harmonic-balance system to ``rtol``: their success is
#: also judged by the recomputed residual. Others (e.g. time integration) judge their own.
RESIDUAL_CHECKED: set[str] = set()


def register(name: str, *, residual_checked: bool = True) -> Callable[[Method], Method]:
    """Register a method under ``name``.

    ``residual_checked``: the method solves the harmonic-balance system to ``rtol``, so a
    recomputed residual above ``rtol`` makes its result unsuccessful.
    """

    def deco(fn: Method) -> Method:
        METHODS[name] = fn
        if residual_checked:
            RESIDUAL_CHECKED.add(name)
        return fn

    return deco
