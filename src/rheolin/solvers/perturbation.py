"""``perturbation``: the seed paper's iteration ``q_{j+1} = A0^-1 (f - dA q_j)``."""

from __future__ import annotations

import numpy as np

from ..harmonics.balance import HarmonicBalance
from .registry import Options, SolverOutcome, register


@register("perturbation")
def solve_perturbation(op: HarmonicBalance, opts: Options) -> SolverOutcome:
    """Fixed-point iteration on the time-averaged system.

    Converges iff the spectral radius of ``A0^-1 dA`` is below one (docs/solvers.md). The
    residual ``f - A q_j = dA (q_{j-1} - q_j)`` comes free from the next right-hand side.
    An initial guess ``x0`` (``options.x0``) is taken as ``q_{-1}``.
    Divergence is detected from the growth of the correction and reported with the
    estimated contraction factor.
    """
    maxiter = 200 if opts.maxiter is None else int(opts.maxiter)
    start = np.zeros_like(op.rhs) if opts.x0 is None else op.apply_dA(opts.x0)
    Q = op.solve_A0(op.rhs - start)  # one step from x0 (from zero: q0 = A0^-1 f)
    dAq = op.apply_dA(Q)
    scale = op.rhs_norm if op.rhs_norm > 0 else 1.0
    history = [op.norm(dAq - start) / scale]  # f - A q = dA (q_{j-1} - q_j)
    if opts.callback:
        opts.callback(0, history[-1])
    rate = float("nan")
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
        rate = _contraction(history)
        if _diverging(history):
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


def _contraction(history: list[float], window: int = 10) -> float:
    """Geometric-mean ratio of successive residuals over the last ``window`` iterations."""
    tail = [h for h in history[-(window + 1) :] if h > 0]
    if len(tail) < 2:
        return float("nan")
    return float((tail[-1] / tail[0]) ** (1.0 / (len(tail) - 1)))


def _diverging(history: list[float]) -> bool:
    """Non-finite, or clearly above both the start and the best residual so far."""
    last = history[-1]
    if not np.isfinite(last):
        return True
    if len(history) < 4:
        return False
    return last > history[0] and last > 10.0 * min(history)
