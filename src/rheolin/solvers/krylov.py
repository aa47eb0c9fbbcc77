"""``gmres``: restarted GMRES on the coupled system, right-preconditioned by ``A0^-1``.

With ``q = A0^-1 y`` the coupled system becomes ``(I + dA A0^-1) y = f``; the GMRES residual
is then the true residual ``f - A q``. Unknowns are the half ``n >= 0`` as a real vector
(real and imaginary parts), weighted so that its 2-norm is the norm over the full set ``H``:
conjugate symmetry halves the solves without changing the iterates (the minimal-residual
coefficients of a conjugate-symmetric Krylov basis are real).

Two strategies, chosen by the size of the support of ``dA`` (the DOFs the time-varying
part touches):

* ``support`` (local time variation: gear meshes, an asymmetric disk). With ``R``, ``C`` the
  rows and columns of ``dA``, ``y - f`` lies in rows ``R``: ``y = f + P_R z`` and
  ``(I + dA_RC G) z = -dA_RC q0_C`` with ``G_n = A0(n)^-1[C, R]`` and ``q0 = A0^-1 f``.
  Its residual equals the true residual. ``G`` costs one ``|R|``-column solve per harmonic;
  then each Krylov iteration is a small dense product, and a final sweep gives ``q``.
* ``full`` (time variation over many DOFs): GMRES on the whole half vector; each iteration
  is one solve sweep and one convolution.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse.linalg as spla

from ..operator import HarmonicBalance
from .registry import Options, SolverOutcome, register

#: Use the ``support`` strategy when ``dA`` touches at most this many DOFs.
MAX_SUPPORT = 64


def _real_gmres(
    apply: Callable[[np.ndarray], np.ndarray],
    rhs: np.ndarray,
    weights: np.ndarray,
    opts: Options,
    scale: float,
    restart: int,
) -> tuple[np.ndarray, int, list[float]]:
    """GMRES over R on half-spectrum complex arrays (rows = harmonics ``n >= 0``).

    ``scale`` converts the residual to the reported one: ``||r|| / scale``.
    """
    shape = rhs.shape
    w = np.sqrt(weights)[:, None]
    size = 2 * rhs.size

    def to_real(Y: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(Y * w).view(np.float64).ravel()

    def to_half(y: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(y).view(np.complex128).reshape(shape) / w

    B = spla.LinearOperator(
        (size, size), matvec=lambda y: to_real(apply(to_half(y))), dtype=np.float64
    )
    b = to_real(rhs)
    bnorm = float(np.linalg.norm(b))
    history: list[float] = []
    if bnorm == 0.0:
        return np.zeros(shape, dtype=complex), 0, history

    def record(rel: float) -> None:
        history.append(float(rel) * bnorm / scale)
        if opts.callback:
            opts.callback(len(history), history[-1])

    maxiter = 500 if opts.maxiter is None else int(opts.maxiter)
    restart = max(1, min(restart, maxiter, size))
    y, info = spla.gmres(
        B,
        b,
        x0=np.zeros(size),
        rtol=min(opts.rtol * scale / bnorm, 0.5),
        atol=0.0,
        restart=restart,
        maxiter=max(1, -(-maxiter // restart)),
        callback=record,
        callback_type="pr_norm",
    )
    return to_half(y), int(info), history


@register("gmres")
def solve_gmres(op: HarmonicBalance, opts: Options) -> SolverOutcome:
    """Krylov solve of the coupled harmonic-balance system (strategy by ``dA``'s support)."""
    rows, cols = op.support
    weights = np.where(op.pos == 0, 1.0, 2.0)
    scale = op.rhs_norm
    if max(rows.size, cols.size) <= MAX_SUPPORT:
        strategy = "support"
        q0 = op.solve_A0(op.rhs)
        G = op.restricted_inverse(cols, rows)  # (|H+|, |C|, |R|)

        def reduced(Z: np.ndarray) -> np.ndarray:
            return Z + op.apply_dA_support((G @ Z[:, :, None])[:, :, 0], rows, cols)

        rhs = -op.apply_dA_support(q0[:, cols], rows, cols)
        Z, info, history = _real_gmres(reduced, rhs, weights, opts, scale, restart=200)
        Y = op.rhs.copy()
        Y[:, rows] += Z
        Q = op.solve_A0(Y)
    else:
        strategy = "full"

        def preconditioned(Y: np.ndarray) -> np.ndarray:
            return Y + op.apply_dA(op.solve_A0(Y))

        Y, info, history = _real_gmres(preconditioned, op.rhs, weights, opts, scale, restart=60)
        Q = op.solve_A0(Y)
    its = len(history)
    extra = {"strategy": strategy, "support": int(max(rows.size, cols.size))}
    if info == 0:
        msg = f"converged in {its} iterations ({strategy} strategy)"
        return SolverOutcome(Q, True, 0, msg, "gmres", its, history, extra)
    if info > 0:
        last = history[-1] if history else float("nan")
        msg = f"gmres did not reach rtol={opts.rtol:g} in {its} iterations (residual {last:.3g})"
        return SolverOutcome(Q, False, 1, msg, "gmres", its, history, extra)
    msg = f"gmres breakdown (info={info})"
    return SolverOutcome(Q, False, 3, msg, "gmres", its, history, extra)
