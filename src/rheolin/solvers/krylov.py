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
* ``band`` (strong time variation over many DOFs: a non-axisymmetric shaft of 10-20 %
  asymmetry, where ``A0^-1`` alone leaves GMRES stalling): the preconditioner holds the wide
  coupling exactly, ``P = A0 + dA_wide`` (the coefficient harmonics whose blocks touch more
  than :data:`MAX_SUPPORT` DOFs, e.g. the ``+-2`` of a rotating asymmetric body), assembled
  over the full set ``H`` and factorized once by the sparse backend (nested dissection keeps
  the fill of its block-banded harmonic structure low); GMRES corrects the local couplings
  left out (gear meshes). ``full`` runs first; after :data:`PROBE_ITERATIONS` iterations
  without converging, ``gmres`` switches to ``band`` when its factor fits the memory budget,
  and says so in the message.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
import scipy.sparse.linalg as spla

from ..operator import HarmonicBalance
from .registry import Options, SolverOutcome, register

#: Use the ``support`` strategy when ``dA`` touches at most this many DOFs.
MAX_SUPPORT = 64
#: ``full`` with a wide coupling: iterations after which ``gmres`` predicts, from the
#: residual's mean rate of decrease, how many more ``full`` needs; more than
#: ``PROBE_ITERATIONS`` more and it switches to ``band``.
PROBE_ITERATIONS = 20


def _real_gmres(
    apply: Callable[[np.ndarray], np.ndarray],
    rhs: np.ndarray,
    weights: np.ndarray,
    opts: Options,
    scale: float,
    restart: int,
    x0: np.ndarray | None = None,
) -> tuple[np.ndarray, int, list[float]]:
    """GMRES over R on half-spectrum complex arrays (rows = harmonics ``n >= 0``).

    ``scale`` converts the residual to the reported one: ``||r|| / scale``; ``x0`` is an
    initial guess (same shape as ``rhs``).
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
        x0=np.zeros(size) if x0 is None else to_real(x0),
        rtol=min(opts.rtol * scale / bnorm, 0.5),
        atol=0.0,
        restart=restart,
        maxiter=max(1, -(-maxiter // restart)),
        callback=record,
        callback_type="pr_norm",
    )
    return to_half(y), int(info), history


#: Refinement steps against the recomputed residual when ``A0^-1`` is approximate (modal).
MAX_REFINEMENTS = 3

Step = Callable[[np.ndarray, "np.ndarray | None"], tuple[np.ndarray, int, list[float]]]


def _better_than_zero(
    apply: Callable[[np.ndarray], np.ndarray],
    rhs: np.ndarray,
    x0: np.ndarray | None,
    norm: Callable[[np.ndarray], float],
) -> np.ndarray | None:
    """``x0`` if its residual is below that of zero (``||rhs||``), else None: a guess from
    a distant speed must not make GMRES start worse than from scratch."""
    if x0 is None or not norm(rhs - apply(x0)) < norm(rhs):
        return None
    return x0


def _support_step(op: HarmonicBalance, opts: Options) -> Step:
    """GMRES on the support of ``dA`` (see the module); returns ``F, x0 -> (Q, info, hist)``."""
    rows, cols = op.support
    weights = np.where(op.pos == 0, 1.0, 2.0)
    G = op.restricted_solver(cols, rows)  # z_n -> A0(n)^-1[C, R] z_n

    def reduced(Z: np.ndarray) -> np.ndarray:
        return Z + op.apply_dA_support(G(Z), rows, cols)

    def step(F: np.ndarray, x0: np.ndarray | None) -> tuple[np.ndarray, int, list[float]]:
        q0 = op.solve_A0(F)
        rhs = -op.apply_dA_support(q0[:, cols], rows, cols)
        Z0 = None if x0 is None else -op.apply_dA_support(x0[:, cols], rows, cols)
        Z0 = _better_than_zero(reduced, rhs, Z0, op.norm)
        Z, info, history = _real_gmres(reduced, rhs, weights, opts, op.rhs_norm, 200, Z0)
        Y = F.copy()
        Y[:, rows] += Z
        return op.solve_A0(Y), info, history

    return step


def _full_step(op: HarmonicBalance, opts: Options) -> Step:
    """GMRES on the whole half vector, right-preconditioned by ``A0^-1``."""
    weights = np.where(op.pos == 0, 1.0, 2.0)

    def preconditioned(Y: np.ndarray) -> np.ndarray:
        return Y + op.apply_dA(op.solve_A0(Y))

    def step(F: np.ndarray, x0: np.ndarray | None) -> tuple[np.ndarray, int, list[float]]:
        Y0 = None if x0 is None else op.apply_A0(x0)
        Y0 = _better_than_zero(preconditioned, F, Y0, op.norm)
        Y, info, history = _real_gmres(preconditioned, F, weights, opts, op.rhs_norm, 60, Y0)
        return op.solve_A0(Y), info, history

    return step


def _band_step(op: HarmonicBalance, opts: Options) -> tuple[Step | None, str]:
    """GMRES right-preconditioned by ``P = A0 + dA_wide`` (see the module); ``None`` and the
    reason when ``P`` does not fit the memory budget or cannot be factorized."""
    from ..budget import format_bytes
    from ..linalg.direct import analyze, resolve_backend

    ks = op.wide_harmonics(MAX_SUPPORT)
    if not ks:
        return None, "no wide coupling to hold"
    P = op.coupled_matrix(ks)
    P.sort_indices()
    name = resolve_backend("auto", (P.indptr, P.indices, P.shape[0]))
    an = analyze(name, P.indptr, P.indices, True, sample=P.data)
    spare = op.budget - op.memory.total
    if an.factor_bytes > spare:
        return None, (
            f"the band preconditioner's factor needs an estimated {format_bytes(an.factor_bytes)}"
            f", more than the {format_bytes(max(spare, 0))} left in the memory budget"
        )
    try:
        factor = an.factor(P.data)
    except (RuntimeError, MemoryError, ValueError) as exc:
        return None, f"the band preconditioner could not be factorized ({exc})"
    weights = np.where(op.pos == 0, 1.0, 2.0)
    nh, nd = op.full.size, op.n_dof

    def inverse(Y: np.ndarray) -> np.ndarray:
        return op.half(np.asarray(factor.solve(op.expand(Y).ravel())).reshape(nh, nd))

    def preconditioned(Y: np.ndarray) -> np.ndarray:
        return op.apply(inverse(Y))

    def step(F: np.ndarray, x0: np.ndarray | None) -> tuple[np.ndarray, int, list[float]]:
        Y0 = None if x0 is None else op.half((P @ op.expand(x0).ravel()).reshape(nh, nd))
        Y0 = _better_than_zero(preconditioned, F, Y0, op.norm)
        Y, info, history = _real_gmres(preconditioned, F, weights, opts, op.rhs_norm, 60, Y0)
        return inverse(Y), info, history

    what = (
        f"band preconditioner: A0 + the coupling of harmonics {', '.join(map(str, ks))} held "
        f"exactly ({P.shape[0]:,} unknowns, {name}, factor {format_bytes(factor.nbytes)})"
    )
    return step, what


def _full_on(
    op: HarmonicBalance, opts: Options, maxiter: int, Q: np.ndarray, history: list[float]
) -> tuple[np.ndarray, int, list[float]]:
    """Go on with the ``full`` strategy from ``Q`` for the iterations left of ``maxiter``."""
    rest = dataclasses.replace(opts, maxiter=maxiter - len(history))
    Q, info, more = _full_step(op, rest)(op.rhs, Q)
    return Q, info, history + more


@register("gmres")
def solve_gmres(op: HarmonicBalance, opts: Options) -> SolverOutcome:
    """Krylov solve of the coupled harmonic-balance system (strategy by ``dA``'s support).

    With an approximate ``A0^-1`` (the modal backend) the answer is refined against the
    recomputed residual ``f - A q`` until it meets ``rtol`` (at most ``MAX_REFINEMENTS``
    extra solves for the correction).
    """
    rows, cols = op.support
    support = int(max(rows.size, cols.size))
    strategy = "support" if support <= MAX_SUPPORT else "full"
    step = _support_step(op, opts) if strategy == "support" else _full_step(op, opts)
    note = ""
    maxiter = 500 if opts.maxiter is None else int(opts.maxiter)
    if strategy == "full" and op.wide_harmonics(MAX_SUPPORT) and maxiter > PROBE_ITERATIONS:
        probe = dataclasses.replace(opts, maxiter=PROBE_ITERATIONS)
        Q, info, history = _full_step(op, probe)(op.rhs, opts.x0)
        if info != 0 and len(history) >= 2 and 0 < history[-1] < history[0]:
            rate = (history[-1] / history[0]) ** (1.0 / (len(history) - 1))
            needed = np.log(opts.rtol / history[-1]) / np.log(rate)
        else:
            needed = np.inf
        if info != 0 and needed <= PROBE_ITERATIONS:  # on its way: full goes on
            Q, info, history = _full_on(op, opts, maxiter, Q, history)
        elif info != 0:
            band, why = _band_step(op, opts)
            if band is not None:
                last = history[-1] if history else float("nan")
                note = (
                    f"the full strategy left residual {last:.2g} after {len(history)} "
                    f"iterations; switched to the {why}"
                )
                strategy, step = "band", band
                Q, info, more = step(op.rhs, opts.x0)
                history = history + more
            else:
                note = f"the full strategy is slow and the band preconditioner was not used: {why}"
                Q, info, history = _full_on(op, opts, maxiter, Q, history)
    else:
        Q, info, history = step(op.rhs, opts.x0)
    refinements = 0
    while info == 0 and not op.inverse.exact and refinements < MAX_REFINEMENTS:
        R = op.residual(Q)
        if op.norm(R) <= opts.rtol * op.rhs_norm:
            break
        dQ, info, more = step(R, None)
        Q, refinements = Q + dQ, refinements + 1
        history += more
    its = len(history)
    extra = {
        "strategy": strategy,
        "support": support,
        "backend": op.inverse.name,
        "refinements": refinements,
        "warm_start": opts.x0 is not None,
    }
    tail = f"; {note}" if note else ""
    if info == 0:
        msg = f"converged in {its} iterations ({strategy} strategy){tail}"
        return SolverOutcome(Q, True, 0, msg, "gmres", its, history, extra)
    if info > 0:
        last = history[-1] if history else float("nan")
        msg = (
            f"gmres did not reach rtol={opts.rtol:g} in {its} iterations (residual {last:.3g})"
            f"{tail}"
        )
        return SolverOutcome(Q, False, 1, msg, "gmres", its, history, extra)
    msg = f"gmres breakdown (info={info}){tail}"
    return SolverOutcome(Q, False, 3, msg, "gmres", its, history, extra)
