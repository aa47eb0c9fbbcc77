"""``gmres``: restarted GMRES on the coupled system, right-preconditioned by ``A0^-1``.

With ``q = A0^-1 y`` the coupled system becomes ``(I + dA A0^-1) y = f``; the GMRES residual
is then the true residual ``f - A q``. Unknowns are the half ``n >= 0`` as a real vector
(real and imaginary parts), weighted so that its 2-norm is the norm over the full set ``H``:
conjugate symmetry halves the solves without changing the iterates (the minimal-residual
coefficients of a conjugate-symmetric Krylov basis are real).

Strategies, chosen by the size of the support of ``dA`` (the DOFs the time-varying part
touches) and by what the system knows of its rotors:

* ``support`` (local time variation: gear meshes, an asymmetric disk). With ``R``, ``C`` the
  rows and columns of ``dA``, ``y - f`` lies in rows ``R``: ``y = f + P_R z`` and
  ``(I + dA_RC G) z = -dA_RC q0_C`` with ``G_n = A0(n)^-1[C, R]`` and ``q0 = A0^-1 f``.
  Its residual equals the true residual. ``G`` costs one ``|R|``-column solve per harmonic;
  then each Krylov iteration is a small dense product, and a final sweep gives ``q``. The
  first few products are solve sweeps instead (a warm start converges before ``G`` pays).
* ``full`` (time variation over many DOFs): GMRES on the whole half vector; each iteration
  is one solve sweep and one convolution.
* ``rows`` (time variation over many DOFs, but on at most :data:`ROWS_SHARE` of them: a
  finely meshed shaft with a flat among plain ones): as ``support``, GMRES on ``z`` over the
  rows ``R`` only, with ``A0^-1`` applied by a solve sweep in every iteration (``G`` would
  take ``|R|`` sweeps) and ``dA`` block by block. The same residual as ``full``, with Krylov
  vectors over ``|R|`` DOFs instead of all of them: less memory and orthogonalization.
* ``band`` (strong time variation over many DOFs: a non-axisymmetric shaft of 10-20 %
  asymmetry, where ``A0^-1`` alone leaves GMRES stalling): the preconditioner holds the wide
  coupling exactly, ``P = A0 + dA_wide`` (the coefficient harmonics whose blocks touch more
  than :data:`MAX_SUPPORT` DOFs, e.g. the ``+-2`` of a rotating asymmetric body), assembled
  over the full set ``H`` and factorized once by the sparse backend (nested dissection keeps
  the fill of its block-banded harmonic structure low); GMRES corrects the local couplings
  left out (gear meshes). ``full`` runs first; after :data:`PROBE_ITERATIONS` iterations
  without converging, ``gmres`` switches to ``band`` when its factor fits the memory budget,
  and says so in the message.
* ``pairs`` (a wide rotating asymmetry, ``+-2``, when the system knows the transverse planes
  of its nodes, ``system.whirl_pairs``; a ``Model`` gives them for bodies along z): in whirl
  coordinates ``f = (x - i y)/sqrt 2``, ``b = (x + i y)/sqrt 2`` the asymmetry couples ``f_m``
  with ``b_{m+2}`` only and an isotropic ``A0`` keeps ``f`` and ``b`` apart, so the coupled
  operator falls into independent chains the size of one harmonic block (the rotating frame
  of the paper's eq. (5), without changing frames). It is tried first: exact on isotropic
  supports (one iteration, about the cost of ``lti``), a preconditioner otherwise (GMRES
  corrects anisotropy and local couplings); when it does not converge the strategies above
  take over.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..budget import format_bytes
from ..harmonics.balance import HarmonicBalance
from ..linalg.memory import ROWS_SHARE
from .gmres_core import Step, gmres_from
from .registry import Options, SolverOutcome, register

#: Use the ``support`` strategy when ``dA`` touches at most this many DOFs.
MAX_SUPPORT = 64
#: ``full`` with a wide coupling: iterations after which ``gmres`` predicts, from the
#: residual's mean rate of decrease, how many more ``full`` needs; more than
#: ``PROBE_ITERATIONS`` more and it switches to ``band``.
PROBE_ITERATIONS = 20


#: Refinement steps against the recomputed residual when ``A0^-1`` is approximate (modal).
MAX_REFINEMENTS = 3

#: GMRES on the support applies ``A0^-1`` by one sweep of solves (one right-hand side per
#: harmonic) up to this many times before it makes ``G`` (``|R|`` right-hand sides per
#: harmonic): a warm start from the previous speed of a sweep converges in a few iterations.
SWEEPS_BEFORE_G = 8


def _restricted(op: HarmonicBalance, rows: np.ndarray, cols: np.ndarray) -> Callable[..., Any]:
    """``z_n -> A0(n)^-1[C, R] z_n``: by solve sweeps while they cost less than making ``G``
    (sparse factors all held, at most :data:`SWEEPS_BEFORE_G` sweeps and a quarter of
    ``|R|``), then by ``G``."""
    inverse = op.inverse
    store = getattr(inverse, "store", None)
    limit = min(SWEEPS_BEFORE_G, rows.size // 4)
    if inverse.name != "lu" or store is None or store.on_demand or limit < 1:
        return op.restricted_solver(cols, rows)
    made: list[Callable[[np.ndarray], np.ndarray]] = []
    sweeps = 0

    def apply(Z: np.ndarray) -> np.ndarray:
        nonlocal sweeps
        if not made and sweeps < limit:
            sweeps += 1
            Y = np.zeros((Z.shape[0], op.n_dof), dtype=complex)
            Y[:, rows] = Z
            return op.solve_A0(Y)[:, cols]
        if not made:
            made.append(op.restricted_solver(cols, rows))
        return made[0](Z)

    return apply


def _support_step(op: HarmonicBalance, opts: Options) -> Step:
    """GMRES on the support of ``dA`` (see the module); returns ``F, x0 -> (Q, info, hist)``."""
    rows, cols = op.support
    weights = np.where(op.pos == 0, 1.0, 2.0)
    G = _restricted(op, rows, cols)  # z_n -> A0(n)^-1[C, R] z_n

    def reduced(Z: np.ndarray) -> np.ndarray:
        return Z + op.apply_dA_support(G(Z), rows, cols)

    def step(F: np.ndarray, x0: np.ndarray | None) -> tuple[np.ndarray, int, list[float]]:
        q0 = op.solve_A0(F)
        rhs = -op.apply_dA_support(q0[:, cols], rows, cols)
        Z0 = None if x0 is None else -op.apply_dA_support(x0[:, cols], rows, cols)
        Z, info, history = gmres_from(
            reduced, rhs, Z0, op.norm, weights, opts, op.rhs_norm, op.memory.restart_length
        )
        Y = F.copy()
        Y[:, rows] += Z
        return op.solve_A0(Y), info, history

    return step


def _rows_step(op: HarmonicBalance, opts: Options) -> Step:
    """GMRES on the rows of ``dA``, ``A0^-1`` by a solve sweep per iteration (the module)."""
    rows = op.support[0]
    weights = np.where(op.pos == 0, 1.0, 2.0)

    def dA_rows(Q: np.ndarray) -> np.ndarray:
        return op.apply_dA(Q)[:, rows]

    def reduced(Z: np.ndarray) -> np.ndarray:
        Y = np.zeros((Z.shape[0], op.n_dof), dtype=complex)
        Y[:, rows] = Z
        return Z + dA_rows(op.solve_A0(Y))

    def step(F: np.ndarray, x0: np.ndarray | None) -> tuple[np.ndarray, int, list[float]]:
        rhs = -dA_rows(op.solve_A0(F))
        Z0 = None if x0 is None else -dA_rows(x0)
        Z, info, history = gmres_from(
            reduced, rhs, Z0, op.norm, weights, opts, op.rhs_norm, op.memory.restart_length
        )
        Y = F.copy()
        Y[:, rows] += Z
        return op.solve_A0(Y), info, history

    return step


def uses_rows(op: HarmonicBalance) -> bool:
    """Whether the ``full`` strategy runs on the rows of ``dA`` only (``rows``, the module)."""
    rows, cols = op.support
    return MAX_SUPPORT < max(rows.size, cols.size) and rows.size <= ROWS_SHARE * op.n_dof


def _full_step(op: HarmonicBalance, opts: Options) -> Step:
    """GMRES on the whole half vector, right-preconditioned by ``A0^-1`` (on the rows of
    ``dA`` only when :func:`uses_rows`)."""
    if uses_rows(op):
        return _rows_step(op, opts)
    weights = np.where(op.pos == 0, 1.0, 2.0)

    def preconditioned(Y: np.ndarray) -> np.ndarray:
        return Y + op.apply_dA(op.solve_A0(Y))

    def step(F: np.ndarray, x0: np.ndarray | None) -> tuple[np.ndarray, int, list[float]]:
        Y0 = None if x0 is None else op.apply_A0(x0)
        Y, info, history = gmres_from(
            preconditioned, F, Y0, op.norm, weights, opts, op.rhs_norm, op.memory.restart_length
        )
        return op.solve_A0(Y), info, history

    return step


def _band_step(op: HarmonicBalance, opts: Options) -> tuple[Step | None, str]:
    """GMRES right-preconditioned by ``P = A0 + dA_wide`` (see the module); ``None`` and the
    reason when ``P`` does not fit the memory budget or cannot be factorized."""
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
        Y, info, history = gmres_from(
            preconditioned, F, Y0, op.norm, weights, opts, op.rhs_norm, op.memory.restart_length
        )
        return inverse(Y), info, history

    what = (
        f"band preconditioner: A0 + the coupling of harmonics {', '.join(map(str, ks))} held "
        f"exactly ({P.shape[0]:,} unknowns, {name}, factor {format_bytes(factor.nbytes)})"
    )
    return step, what


def _pairs_step(op: HarmonicBalance, opts: Options) -> tuple[Step | None, str]:
    """GMRES right-preconditioned by the whirl-pair operator (see the module); ``None`` and
    the reason when the system has no whirl pairs or other wide couplings than ``+-2``.

    In the coordinates ``f = (x - i y) / sqrt 2``, ``b = (x + i y) / sqrt 2`` of every plane
    (``system.whirl_pairs``), a rotating asymmetry couples ``f`` at harmonic ``m`` only with
    ``b`` at ``m + 2``, and an isotropic ``A0`` keeps ``f`` and ``b`` apart: the coupled
    operator falls into independent chains ``(f_m, b_{m+2})`` (and every other DOF at its own
    harmonic), each the size of one harmonic block. The preconditioner keeps exactly the
    blocks inside the chains (for an asymmetric rotor on isotropic supports: the inverse
    itself), assembles and factorizes a chain when a residual first reaches it (an unloaded
    chain, e.g. of the even harmonics under unbalance, never), and GMRES corrects what it
    leaves out (anisotropic bearings, gear meshes, axial-torsional couplings).
    """
    from ..linalg.direct import analyze

    pairs = getattr(op.system, "whirl_pairs", None)
    if pairs is None:
        return None, "no whirl planes known"
    ks = op.wide_harmonics(MAX_SUPPORT)
    if not ks or set(ks) - {-2, 2}:
        return None, "the wide coupling is not a rotating asymmetry (harmonics +-2)"
    system = op.system
    nd, H, w1 = op.n_dof, op.full, op.w1
    at = {int(h): i for i, h in enumerate(H)}
    ix, iy = (np.asarray(p, dtype=np.int64) for p in pairs)
    other = np.setdiff1d(np.arange(nd), np.concatenate([ix, iy]))
    r2 = 1.0 / np.sqrt(2.0)
    # U: columns f_j = (e_x + i e_y) / sqrt 2 and b_j = (e_x - i e_y) / sqrt 2 (q = U z)
    TF = sp.csc_array(
        (np.concatenate([np.full(ix.size, r2), np.full(ix.size, 1j * r2)]),
         (np.concatenate([ix, iy]), np.tile(np.arange(ix.size), 2))),
        shape=(nd, ix.size),
    )  # fmt: skip
    TB = TF.conj()
    TO = sp.csc_array((np.ones(other.size), (other, np.arange(other.size))), shape=(nd, other.size))
    # the sense the asymmetry turns: forward maps f -> b across +2, backward b -> f (then the
    # chains are (b_m, f_m+2): the roles swap); the share of its coupling the chains hold
    X2 = sp.csr_array(system.K[2]) if 2 in system.K else None
    held = 1.0
    if X2 is not None:
        parts = {
            (a, b): float(spla.norm(Ta.conj().T @ X2 @ Tb))
            for a, Ta in (("f", TF), ("b", TB))
            for b, Tb in (("f", TF), ("b", TB))
        }
        total = sum(v * v for v in parts.values()) or 1.0
        if parts[("f", "b")] > parts[("b", "f")]:
            TF, TB = TB, TF
        held = max(parts[("b", "f")], parts[("f", "b")]) ** 2 / total

    def X(k: int, h: int) -> Any:
        """``K_k + s D_k + s^2 M_k`` at the column harmonic ``h``."""
        sv = 1j * w1 * h
        out = sp.csr_array((nd, nd), dtype=complex)
        for table, power in ((system.K, 0), (system.D, 1), (system.M, 2)):
            if k in table:
                out = out + sv**power * sp.csr_array(table[k])
        return out

    def chain_matrix(kind: str, m: int) -> Any:
        if kind == "o":
            return sp.csc_array(TO.T @ X(0, m) @ TO)
        has_f, has_b = m in at, m + 2 in at
        blocks: list[list[Any]] = [[None, None], [None, None]]
        if has_f:
            blocks[0][0] = TF.conj().T @ X(0, m) @ TF
        if has_b:
            blocks[1][1] = TB.conj().T @ X(0, m + 2) @ TB
        if has_f and has_b:
            if -2 in ks:
                blocks[0][1] = TF.conj().T @ X(-2, m + 2) @ TB
            if 2 in ks:
                blocks[1][0] = TB.conj().T @ X(2, m) @ TF
        keep = [i for i, ok in enumerate((has_f, has_b)) if ok]
        return sp.csc_array(sp.block_array([[blocks[i][j] for j in keep] for i in keep]))

    chains = [("p", m) for m in sorted({int(h) for h in H} | {int(h) - 2 for h in H})]
    if other.size:
        chains += [("o", int(h)) for h in H]
    factors: dict[tuple[str, int], Any] = {}

    def chain_solve(c: tuple[str, int], r: np.ndarray) -> np.ndarray:
        if c not in factors:
            A = chain_matrix(*c)
            A.sort_indices()
            try:
                factors[c] = analyze("superlu", A.indptr, A.indices, True).factor(A.data)
            except (RuntimeError, ValueError) as exc:
                raise RuntimeError(f"a whirl-pair chain is singular ({exc})") from None
        return np.asarray(factors[c].solve(r))

    weights = np.where(op.pos == 0, 1.0, 2.0)
    nf = ix.size

    def inverse(Y: np.ndarray) -> np.ndarray:
        R = op.expand(Y)  # (|H|, n)
        RF, RB, RO = R @ TF.conj(), R @ TB.conj(), R[:, other]  # z = U^H r per harmonic
        XF, XB = np.zeros_like(RF), np.zeros_like(RB)
        XO = np.zeros_like(RO)
        for kind, m in chains:
            if kind == "o":
                r = RO[at[m]]
                if np.any(r):
                    XO[at[m]] = chain_solve((kind, m), r)
                continue
            parts = []
            if m in at:
                parts.append(RF[at[m]])
            if m + 2 in at:
                parts.append(RB[at[m + 2]])
            r = np.concatenate(parts)
            if not np.any(r):  # an unloaded chain stays zero
                continue
            x = chain_solve((kind, m), r)
            if m in at:
                XF[at[m]], x = x[:nf], x[nf:]
            if m + 2 in at:
                XB[at[m + 2]] = x
        Xq = XF @ TF.T + XB @ TB.T  # q = U z per harmonic
        if other.size:
            Xq[:, other] += XO
        return op.half(Xq)

    def preconditioned(Y: np.ndarray) -> np.ndarray:
        return op.apply(inverse(Y))

    def step(F: np.ndarray, x0: np.ndarray | None) -> tuple[np.ndarray, int, list[float]]:
        Y0 = None if x0 is None else op.apply(x0)
        Y, info, history = gmres_from(
            preconditioned, F, Y0, op.norm, weights, opts, op.rhs_norm, op.memory.restart_length
        )
        return inverse(Y), info, history

    what = (
        f"whirl-pair preconditioner: {held:.0%} of the rotating asymmetry held exactly in "
        "independent (f_m, b_m+2) chains, each factorized when first reached"
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
    solved, tried = False, ""
    if strategy == "full" and op.wide_harmonics(MAX_SUPPORT):
        pairs, pairs_what = _pairs_step(op, opts)
        if pairs is not None:
            Q, info, history = pairs(op.rhs, opts.x0)
            if info == 0:
                strategy, step, note, solved = "pairs", pairs, pairs_what, True
            else:  # what the chains leave out is too strong: the A0 strategies from scratch
                tried = f"the whirl-pair preconditioner did not converge ({len(history)} its); "
    if solved:
        pass
    elif strategy == "full" and op.wide_harmonics(MAX_SUPPORT) and maxiter > PROBE_ITERATIONS:
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
    # the pairs preconditioner is a direct factor of its own: A0's (possibly modal,
    # approximate) inverse is not built, and needs no refinement against
    uses_a0 = strategy != "pairs"
    while info == 0 and uses_a0 and not op.inverse.exact and refinements < MAX_REFINEMENTS:
        R = op.residual(Q)
        if op.norm(R) <= opts.rtol * op.rhs_norm:
            break
        dQ, info, more = step(R, None)
        Q, refinements = Q + dQ, refinements + 1
        history += more
    its = len(history)
    if strategy == "full" and uses_rows(op):
        strategy = "rows"
    extra = {
        "strategy": strategy,
        "support": support,
        "backend": op.inverse.name if uses_a0 else "lu (whirl-pair chains)",
        "refinements": refinements,
        "warm_start": opts.x0 is not None,
        "restart": op.memory.restart_length,
    }
    note = tried + note
    if strategy != "pairs" and op.memory.restart_length < op.memory.default_restart:
        note += (
            f"{'; ' if note else ''}GMRES restarted every {op.memory.restart_length} "
            f"iterations (not {op.memory.default_restart}) to fit the memory budget of "
            f"{format_bytes(op.budget)}"
        )
    tail = f"; {note}" if note else ""
    if info == 0:
        msg = f"converged in {its} iterations ({strategy} strategy){tail}"
        return SolverOutcome(Q, True, 0, msg, "gmres", its, history, extra)
    if info > 0:
        # the recomputed residual: the Krylov estimate (``history``) reads 0 where the
        # preconditioner is singular to round-off (an undamped resonance under PARDISO)
        last = op.relative_residual(Q)
        msg = (
            f"gmres did not reach rtol={opts.rtol:g} in {its} iterations (relative residual "
            f"{last:.3g}){tail}"
        )
        return SolverOutcome(Q, False, 1, msg, "gmres", its, history, extra)
    msg = f"gmres breakdown (info={info}){tail}"
    return SolverOutcome(Q, False, 3, msg, "gmres", its, history, extra)
