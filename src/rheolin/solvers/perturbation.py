"""``perturbation``: the seed paper's iteration ``q_{j+1} = A0^-1 (f - dA q_j)``."""

from __future__ import annotations

import numpy as np

from ..operator import HarmonicBalance
from .registry import Options, SolverOutcome, register


@register("perturbation")
def solve_perturbation(op: HarmonicBalance, opts: Options) -> SolverOutcome:
    """Fixed-point iteration on the time-averaged system.

    Converges iff the spectral radius of ``A0^-1 dA`` is below one (DESIGN.md §3). The
    residual ``f - A q_j = dA (q_{j-1} - q_j)`` comes free from the next right-hand side.
    Divergence is detected from the growth of the correction and reported with the
    estimated contraction factor.
    """
    maxiter = 200 if opts.maxiter is None else int(opts.maxiter)
    Q = op.solve_A0(op.rhs)
    dAq = op.apply_dA(Q)
    scale = op.rhs_norm if op.rhs_norm > 0 else 1.0
    history = [op.norm(dAq) / scale]  # residual of q0: f - A0 q0 - dA q0 = -dA q0
    if opts.callback:
        opts.callback(0, history[-1])
    rate = float("nan")
    growth = 0
    for it in range(1, maxiter + 1):
        if history[-1] <= opts.rtol:
            return SolverOutcome(
                Q, True, 0, f"converged in {it - 1} iterations", "perturbation", it - 1, history
            )
        Q = op.solve_A0(op.rhs - dAq)
        dAq_new = op.apply_dA(Q)
        history.append(op.norm(dAq_new - dAq) / scale)
        dAq = dAq_new
        if opts.callback:
            opts.callback(it, history[-1])
        if len(history) >= 3 and history[-2] > 0:
            rate = history[-1] / history[-2]
        growth = growth + 1 if history[-1] > history[-2] else 0
        if not np.isfinite(history[-1]) or (growth >= 3 and history[-1] > history[0]):
            return SolverOutcome(
                Q,
                False,
                2,
                "perturbation iteration diverged: the spectral radius of A0^-1 dA is >= 1 "
                f"(estimated contraction factor {rate:.3g}); use method='gmres'",
                "perturbation",
                it,
                history,
                {"contraction": rate},
            )
    if history[-1] <= opts.rtol:
        return SolverOutcome(
            Q, True, 0, f"converged in {maxiter} iterations", "perturbation", maxiter, history
        )
    return SolverOutcome(
        Q,
        False,
        1,
        f"perturbation iteration did not reach rtol={opts.rtol:g} in {maxiter} iterations "
        f"(residual {history[-1]:.3g}, contraction factor {rate:.3g})",
        "perturbation",
        maxiter,
        history,
        {"contraction": rate},
    )
