"""Memory of a harmonic-balance solve, estimated before anything large is allocated.

``estimate = factors held + Krylov basis + vectors`` where

* one factor of ``A0(n)`` takes what the sparse backend's symbolic analysis reports (PARDISO:
  exact before factorizing; UMFPACK/SuperLU: measured on the first factor), and the factors
  of as many harmonics as fit the budget are held (at least one: past that, refactorized on
  demand, :class:`~rheolin.linalg.store.FactorStore`);
* the Krylov basis of GMRES: ``restart + 1`` real vectors of the half set (``full`` strategy)
  or of the support of the time variation and its blocks ``G_n`` (``support`` strategy);
* the vectors: load, solution, residual, the two-sided result and temporaries, about
  :data:`VECTOR_COPIES` complex arrays of ``|H+| x n``.

A solve that cannot fit even with a single factor is refused (:func:`check`) with the
estimate and what to change, before the operator allocates its load vector.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..budget import MemoryBudgetError, format_bytes

__all__ = ["ROWS_SHARE", "VECTOR_COPIES", "SolveMemory", "check"]

#: Complex ``|H+| x n`` arrays alive during a solve (load, iterate, residual, products,
#: the two-sided result ``|H| x n``, which counts twice).
VECTOR_COPIES = 8
#: GMRES restart lengths of the two strategies (:mod:`rheolin.solvers.krylov`).
FULL_RESTART = 60
SUPPORT_RESTART = 200
#: The ``full`` strategy runs its Krylov vectors over the rows of the time variation only
#: when they are at most this share of the DOFs (the ``rows`` strategy).
ROWS_SHARE = 0.5


@dataclass
class SolveMemory:
    """The parts of the estimate [bytes]; ``factors_held`` of ``harmonics`` factors."""

    n_dof: int
    harmonics: int
    support: int
    factor_bytes: int = 0
    factors_held: int = 0

    @property
    def vectors(self) -> int:
        """Load, solution, residual and result arrays."""
        return VECTOR_COPIES * self.harmonics * self.n_dof * 16

    @property
    def krylov(self) -> int:
        """GMRES basis (and the support blocks ``G_n``) of the larger strategy."""
        if self.support == 0:
            return 0
        if self.support <= 64:
            basis = (SUPPORT_RESTART + 1) * 2 * self.harmonics * self.support * 8
            return basis + self.harmonics * self.support**2 * 16
        width = self.support if self.support <= ROWS_SHARE * self.n_dof else self.n_dof
        return (FULL_RESTART + 1) * 2 * self.harmonics * width * 8

    @property
    def factors(self) -> int:
        """Factors held at once."""
        return self.factor_bytes * self.factors_held

    @property
    def total(self) -> int:
        """Everything above."""
        return self.vectors + self.krylov + self.factors

    def describe(self) -> str:
        """One line: the parts and the total."""
        held = (
            f"{self.factors_held} factors x {format_bytes(self.factor_bytes)}"
            if self.factor_bytes
            else "factors not yet analysed"
        )
        return (
            f"{format_bytes(self.total)} ({held}, Krylov {format_bytes(self.krylov)}, "
            f"vectors {format_bytes(self.vectors)} for {self.harmonics} harmonics x "
            f"{self.n_dof} DOF)"
        )


def check(memory: SolveMemory, budget: int) -> None:
    """Raise :class:`MemoryBudgetError` when ``memory`` (with at least one factor) exceeds
    ``budget``, saying what to change.

    >>> check(SolveMemory(n_dof=10, harmonics=5, support=0), 10**6)
    >>> check(SolveMemory(n_dof=10**6, harmonics=10**4, support=0), 10**9)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rheolin.budget.MemoryBudgetError: the harmonic-balance solve needs an estimated 1.28e+03 GB ...
    """
    if memory.total <= budget:
        return
    per_harmonic = VECTOR_COPIES * memory.n_dof * 16 + memory.krylov // max(memory.harmonics, 1)
    fit = max(0, (budget - memory.factors) // max(per_harmonic, 1))
    raise MemoryBudgetError(
        f"the harmonic-balance solve needs an estimated {memory.describe()}, more than the "
        f"memory budget of {format_bytes(budget)}. Reduce the harmonics (about {fit} would "
        "fit: lower the closure order or max_order), reduce the model (fewer modes or a "
        "coarser mesh in condensed bodies), or raise the budget (RHEOLIN_SOLVE_MEMORY, "
        "memory_budget=) on a larger machine"
    )
