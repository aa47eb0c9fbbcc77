"""The time-domain baseline: BDF from rest until the response is periodic (docs/solvers.md)."""

from .method import solve_transient
from .settings import DEFAULTS, TransientSettings, sundae_available

__all__ = ["DEFAULTS", "TransientSettings", "solve_transient", "sundae_available"]
