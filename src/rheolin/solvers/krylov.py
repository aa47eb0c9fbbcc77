"""``gmres``: restarted GMRES on the coupled system, right-preconditioned by ``A0^-1``.

With ``q = A0^-1 y`` the coupled system becomes ``(I + dA A0^-1) y = f``; the GMRES residual
is then the true residual ``f - A q``. The unknowns are the half ``n >= 0`` as a real vector
(real and imaginary parts), weighted so that its 2-norm is the norm over the full set ``H``:
conjugate symmetry halves the solves without changing the iterates (the minimal-residual
coefficients of a conjugate-symmetric Krylov basis are real).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

from ..operator import HarmonicBalance
from .registry import Options, SolverOutcome, register


@register("gmres")
def solve_gmres(op: HarmonicBalance, opts: Options, *, restart: int = 60) -> SolverOutcome:
    """Krylov solve of the coupled harmonic-balance system."""
    shape = op.rhs.shape
    w = np.sqrt(np.where(op.pos == 0, 1.0, 2.0))[:, None]
    size = 2 * op.rhs.size

    def to_real(Y: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(Y * w).view(np.float64).ravel()

    def to_half(y: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(y).view(np.complex128).reshape(shape) / w

    def matvec(y: np.ndarray) -> np.ndarray:
        Y = to_half(y)
        return to_real(Y + op.apply_dA(op.solve_A0(Y)))

    B = spla.LinearOperator((size, size), matvec=matvec, dtype=np.float64)
    b = to_real(op.rhs)
    maxiter = 500 if opts.maxiter is None else int(opts.maxiter)
    restart = max(1, min(restart, maxiter, size))
    history: list[float] = []

    def record(rel: float) -> None:
        history.append(float(rel))
        if opts.callback:
            opts.callback(len(history), float(rel))

    y0 = np.zeros(size)
    # GMRES counts outer cycles; we budget inner iterations.
    cycles = max(1, -(-maxiter // restart))
    y, info = spla.gmres(
        B,
        b,
        x0=y0,
        rtol=opts.rtol,
        atol=0.0,
        restart=restart,
        maxiter=cycles,
        callback=record,
        callback_type="pr_norm",
    )
    Q = op.solve_A0(to_half(y))
    its = len(history)
    if info == 0:
        return SolverOutcome(Q, True, 0, f"converged in {its} iterations", "gmres", its, history)
    if info > 0:
        last = history[-1] if history else float("nan")
        return SolverOutcome(
            Q,
            False,
            1,
            f"gmres did not reach rtol={opts.rtol:g} in {its} iterations (residual {last:.3g})",
            "gmres",
            its,
            history,
        )
    return SolverOutcome(Q, False, 3, f"gmres breakdown (info={info})", "gmres", its, history)
