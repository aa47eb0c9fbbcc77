"""``direct``: the assembled block-sparse coupled system, sparse LU (the reference)."""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse.linalg as spla

from ..budget import format_bytes
from ..harmonics.balance import HarmonicBalance
from .registry import Options, SolverOutcome, register

#: Refuse to assemble coupled systems with more stored entries than this.
MAX_COUPLED_NNZ = 200_000_000

#: SuperLU's factor (partial pivoting, ``MMD_AT_PLUS_A``) against PARDISO's symbolic analysis
#: of the same pattern (METIS): 4.1 and 5.5 times the entries on the gearbox's coupled
#: matrices of 30,114 and 83,034 unknowns; the estimate takes this many.
SUPERLU_FILL = 6.0

#: Bytes per stored factor entry (complex value, row index), per matrix entry that the
#: symbolic analysis needs at most (0.07 GB per million entries measured) and per entry while
#: the coupled matrix is assembled (coordinates, values, their concatenation and the CSC copy).
ENTRY_BYTES = 20
ANALYSIS_BYTES = 100
ASSEMBLY_BYTES = 80

#: Without PARDISO no analysis predicts the factor: the coupled matrix is factorized only
#: up to this many unknowns.
UNANALYSED_UNKNOWNS = 100_000


#: What to change when the direct method does not fit.
ADVICE = (
    "use method='gmres' (the time-averaged system must be regular at every harmonic: "
    "damp an undamped resonance), fewer harmonics or a smaller model, or raise the "
    "budget (RHEOLIN_SOLVE_MEMORY or memory_budget=)"
)


@register("direct")
def solve_direct(op: HarmonicBalance, opts: Options) -> SolverOutcome:
    """Assemble the coupled matrix over the full set ``H`` and factorize it."""
    entries = op.coupled_entries()  # counted before anything is assembled
    if entries > MAX_COUPLED_NNZ:
        return _failed(op, f"coupled matrix too large for method='direct' ({entries} nonzeros)")
    if ASSEMBLY_BYTES * entries > op.budget:
        return _failed(
            op,
            f"method='direct': assembling the coupled matrix ({entries:,} entries) needs an "
            f"estimated {format_bytes(ASSEMBLY_BYTES * entries)}, more than the memory budget "
            f"of {format_bytes(op.budget)}; {ADVICE}",
        )
    A = op.coupled_matrix()
    refused = factor_refusal(A, op.budget)
    if refused:
        return _failed(op, refused)
    try:
        lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A")  # partial pivoting: the reference
    except RuntimeError as exc:
        return _failed(op, f"coupled matrix is singular ({exc})")
    except MemoryError:
        return _failed(op, "out of memory factorizing the coupled matrix")
    x = lu.solve(op.full_rhs().ravel())
    Q = op.half(x.reshape(op.full.size, op.n_dof))
    return SolverOutcome(Q, True, 0, "solved the coupled system by sparse LU", "direct")


def factor_estimate(A: Any) -> int | None:
    """Bytes the SuperLU factor of the coupled matrix ``A`` and the matrix take, estimated
    before factorizing: the factor's entries from PARDISO's symbolic analysis of the pattern
    times :data:`SUPERLU_FILL` (None: PARDISO is not installed)."""
    from ..linalg.direct import available_backends

    if "pardiso" not in available_backends():
        return None
    from ..linalg.direct.pardiso import PardisoAnalysis

    A.sort_indices()
    analysis = PardisoAnalysis(A.indptr, A.indices, bool(np.iscomplexobj(A.data)))
    entries = SUPERLU_FILL * analysis.factor_nnz
    analysis.release()  # its memory is returned before the factorization
    return int(ENTRY_BYTES * (entries + A.nnz))


def factor_refusal(A: Any, budget: int) -> str:
    """Why the sparse LU of the coupled matrix ``A`` cannot run within ``budget`` bytes (""
    when it can), from :func:`factor_estimate`. The OS would otherwise decide: SuperLU
    allocates as it fills, and the coupled matrix of a 50,000-DOF gearbox on 330 harmonics
    went past 19 GB under a budget of 16 GB."""
    n = int(A.shape[0])
    head = f"method='direct': the sparse LU of the coupled matrix ({n:,} unknowns)"
    if ANALYSIS_BYTES * A.nnz > budget:
        return (
            f"{head} cannot even be analysed within the memory budget of "
            f"{format_bytes(budget)} ({A.nnz:,} entries); {ADVICE}"
        )
    estimate = factor_estimate(A)
    if estimate is None:
        if n > UNANALYSED_UNKNOWNS:
            return (
                f"{head} has no estimate of its factor here (PARDISO is not installed) and is "
                f"factorized only up to {UNANALYSED_UNKNOWNS:,} unknowns; {ADVICE}"
            )
        return ""
    if estimate > budget:
        return (
            f"{head} needs an estimated {format_bytes(estimate)} (its symbolic analysis's "
            f"factor entries times {SUPERLU_FILL:g} for SuperLU's partial pivoting), more "
            f"than the memory budget of {format_bytes(budget)}; {ADVICE}"
        )
    return ""


def _failed(op: HarmonicBalance, message: str) -> SolverOutcome:
    """The outcome of a direct solve that did not run (status 3, no response)."""
    return SolverOutcome(np.zeros_like(op.rhs), False, 3, message, "direct")
