"""``lti``: independent per-frequency solves of a time-invariant system (seed eq. 2)."""

from __future__ import annotations

from ..errors import ModelError
from ..harmonics.balance import HarmonicBalance
from .registry import Options, SolverOutcome, register


@register("lti")
def solve_lti(op: HarmonicBalance, opts: Options) -> SolverOutcome:
    """``q_n = A0(n)^-1 f_n``; refuses a system with time-varying coefficients."""
    if op.system.coefficient_harmonics:
        raise ModelError(
            "--method / method='lti' needs time-invariant M, D, K, but the system has coefficient "
            f"harmonics {op.system.coefficient_harmonics}; use 'gmres', 'perturbation', "
            "'direct' or 'auto'"
        )
    Q = op.solve_A0(op.rhs)
    return SolverOutcome(Q, True, 0, "solved the time-invariant system directly", "lti")
