"""Registry of steady-state methods: each takes the operator and options, returns an outcome."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..operator import HarmonicBalance

__all__ = ["METHODS", "Options", "SolverOutcome", "register"]


@dataclass
class Options:
    """Keyword options shared by every method."""

    rtol: float = 1e-10
    maxiter: int | None = None
    callback: Callable[[int, float], None] | None = None


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


def register(name: str) -> Callable[[Method], Method]:
    """Register a method under ``name``."""

    def deco(fn: Method) -> Method:
        METHODS[name] = fn
        return fn

    return deco
