"""``direct``: the assembled block-sparse coupled system, sparse LU (the reference)."""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

from ..harmonics.balance import HarmonicBalance
from .registry import Options, SolverOutcome, register

#: Refuse to assemble coupled systems with more stored entries than this.
MAX_COUPLED_NNZ = 200_000_000


@register("direct")
def solve_direct(op: HarmonicBalance, opts: Options) -> SolverOutcome:
    """Assemble the coupled matrix over the full set ``H`` and factorize it."""
    A = op.coupled_matrix()
    if A.nnz > MAX_COUPLED_NNZ:
        return SolverOutcome(
            np.zeros_like(op.rhs),
            False,
            3,
            f"coupled matrix too large for method='direct' ({A.nnz} nonzeros)",
            "direct",
        )
    try:
        lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A")  # partial pivoting: the reference
    except RuntimeError as exc:
        return SolverOutcome(
            np.zeros_like(op.rhs), False, 3, f"coupled matrix is singular ({exc})", "direct"
        )
    except MemoryError:
        return SolverOutcome(
            np.zeros_like(op.rhs),
            False,
            3,
            "out of memory factorizing the coupled matrix",
            "direct",
        )
    x = lu.solve(op.full_rhs().ravel())
    Q = op.half(x.reshape(op.full.size, op.n_dof))
    return SolverOutcome(Q, True, 0, "solved the coupled system by sparse LU", "direct")
