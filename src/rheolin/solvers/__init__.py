"""Steady-state solvers: one entry point, :func:`solve`, over a registry of methods."""

from .registry import METHODS, SolverOutcome, register
from .solve import solve

__all__ = ["METHODS", "SolverOutcome", "register", "solve"]
