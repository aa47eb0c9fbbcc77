"""GMRES over the reals on half-spectrum complex arrays (rows = harmonics ``n >= 0``), the
iteration every strategy of :mod:`rheolin.solvers.krylov` runs.

Conjugate symmetry halves the unknowns without changing the iterates: the minimal-residual
coefficients of a conjugate-symmetric Krylov basis are real, so GMRES runs on the real and
imaginary parts, weighted so that the 2-norm is the norm over the full harmonic set.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse.linalg as spla

from .registry import Options

__all__ = ["Step", "gmres_from", "real_gmres"]

#: One solve of a strategy: ``(F, x0) -> (Q, info, residual history)``.
Step = Callable[[np.ndarray, "np.ndarray | None"], tuple[np.ndarray, int, list[float]]]


def real_gmres(
    apply: Callable[[np.ndarray], np.ndarray],
    rhs: np.ndarray,
    weights: np.ndarray,
    opts: Options,
    scale: float,
    restart: int,
) -> tuple[np.ndarray, int, list[float]]:
    """GMRES over R on half-spectrum complex arrays (rows = harmonics ``n >= 0``), from zero
    (:func:`gmres_from` starts from a guess).

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
    # underflow in SciPy's own norms is harmless: the squares of entries below 1e-154 are
    # flushed to zero (SciPy 1.17 meets them on a planetary set in inertial axes)
    with np.errstate(under="ignore"):
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


def gmres_from(
    apply: Callable[[np.ndarray], np.ndarray],
    rhs: np.ndarray,
    x0: np.ndarray | None,
    norm: Callable[[np.ndarray], float],
    weights: np.ndarray,
    opts: Options,
    scale: float,
    restart: int,
) -> tuple[np.ndarray, int, list[float]]:
    """GMRES from ``x0`` when its residual is below that of zero (``||rhs||``), else from
    zero: a guess from a distant speed must not make GMRES start worse than from scratch.
    From ``x0`` it solves for the correction, ``A dx = rhs - A x0`` from zero, which is the
    same iteration without SciPy's second product for the same initial residual (one
    product fewer per solve)."""
    if x0 is not None:
        r0 = rhs - apply(x0)
        start = norm(r0)
        if start < opts.rtol * scale:  # converged already (SciPy's own first test)
            return x0, 0, []
        if start < norm(rhs):
            dx, info, history = real_gmres(apply, r0, weights, opts, scale, restart)
            return x0 + dx, info, history
    return real_gmres(apply, rhs, weights, opts, scale, restart)
