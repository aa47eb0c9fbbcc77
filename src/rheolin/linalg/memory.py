"""Memory of a harmonic-balance solve, estimated before anything large is allocated.

``estimate = factors held + Krylov basis + vectors`` where

* one factor of ``A0(n)`` takes what the sparse backend's symbolic analysis reports (PARDISO:
  exact before factorizing; UMFPACK/SuperLU: measured on the first factor), and the factors
  of as many harmonics as fit the budget are held (at least one: past that, refactorized on
  demand, :class:`~rheolin.linalg.store.FactorStore`);
* the Krylov basis of GMRES: ``restart + 1`` real vectors of the half set (``full`` strategy)
  or of the support of the time variation and its blocks ``G_n`` (``support`` strategy). The
  restart is the strategy's own (:data:`FULL_RESTART`, :data:`SUPPORT_RESTART`) when that
  fits the budget, else the longest that does, down to :data:`MIN_RESTART`
  (:meth:`SolveMemory.fit`): a basis grows with the iterations only up to its restart, and a
  solve that converges in fewer iterations than the restart never holds more;
* the vectors: load, solution, residual, the two-sided result and temporaries, about
  :data:`VECTOR_COPIES` complex arrays of ``|H+| x n``.

A solve that cannot fit even with a single factor is refused (:func:`check`) with the
estimate and what to change, before the operator allocates its load vector.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..budget import MemoryBudgetError, format_bytes

__all__ = ["MIN_RESTART", "ROWS_SHARE", "VECTOR_COPIES", "SolveMemory", "check"]

#: Complex ``|H+| x n`` arrays alive during a solve (load, iterate, residual, products,
#: the two-sided result ``|H| x n``, which counts twice).
VECTOR_COPIES = 8
#: GMRES restart lengths of the two strategies (:mod:`rheolin.solvers.krylov`).
FULL_RESTART = 60
SUPPORT_RESTART = 200
#: The shortest restart a solve is given to fit its budget; a harmonic set that does not fit
#: even with it (and one factor) is refused.
MIN_RESTART = 20
#: The ``full`` strategy runs its Krylov vectors over the rows of the time variation only
#: when they are at most this share of the DOFs (the ``rows`` strategy).
ROWS_SHARE = 0.5


@dataclass
class SolveMemory:
    """The parts of the estimate [bytes]; ``factors_held`` of ``harmonics`` factors;
    ``restart`` the GMRES restart length (None: the strategy's own, :attr:`default_restart`).

    >>> m = SolveMemory(n_dof=1000, harmonics=100, support=600)
    >>> m.restart_length, m.fit(m.total - 1), m.fit(10**9), m.fit(1)
    (60, 59, 60, 20)
    """

    n_dof: int
    harmonics: int
    support: int
    factor_bytes: int = 0
    factors_held: int = 0
    restart: int | None = None

    @property
    def default_restart(self) -> int:
        """The restart of the strategy the estimate counts (``support`` up to 64 DOFs)."""
        return SUPPORT_RESTART if 0 < self.support <= 64 else FULL_RESTART

    @property
    def restart_length(self) -> int:
        """The restart GMRES is run with."""
        return self.default_restart if self.restart is None else int(self.restart)

    def fit(self, budget: int) -> int:
        """Set :attr:`restart` to the longest up to :attr:`default_restart` with which the
        estimate fits ``budget`` (at least :data:`MIN_RESTART`, which may not fit:
        :func:`check` says so) and return it."""
        top = self.default_restart
        self.restart = top
        per = self._krylov_per_vector()
        if per == 0 or self.total <= budget:
            return top
        room = budget - self.vectors - self.factors - self._krylov_fixed()
        self.restart = int(min(top, max(MIN_RESTART, room // per - 1)))
        return self.restart

    def _krylov_per_vector(self) -> int:
        """Bytes of one Krylov vector of the basis."""
        if self.support == 0:
            return 0
        if self.support <= 64:
            return 2 * self.harmonics * self.support * 8
        width = self.support if self.support <= ROWS_SHARE * self.n_dof else self.n_dof
        return 2 * self.harmonics * width * 8

    def _krylov_fixed(self) -> int:
        """Bytes of the support blocks ``G_n`` (``support`` strategy)."""
        return self.harmonics * self.support**2 * 16 if 0 < self.support <= 64 else 0

    @property
    def vectors(self) -> int:
        """Load, solution, residual and result arrays."""
        return VECTOR_COPIES * self.harmonics * self.n_dof * 16

    @property
    def krylov(self) -> int:
        """GMRES basis (and the support blocks ``G_n``) of the larger strategy."""
        return (self.restart_length + 1) * self._krylov_per_vector() + self._krylov_fixed()

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
            f"{format_bytes(self.total)} ({held}, Krylov {format_bytes(self.krylov)} with "
            f"restart {self.restart_length}, "
            f"vectors {format_bytes(self.vectors)} for {self.harmonics} harmonics x "
            f"{self.n_dof} DOF)"
        )


def check(memory: SolveMemory, budget: int) -> None:
    """Raise :class:`MemoryBudgetError` when ``memory`` (with at least one factor) exceeds
    ``budget`` even with the shortest GMRES restart, saying what to change; otherwise fit
    its restart to the budget (:meth:`SolveMemory.fit`).

    >>> check(SolveMemory(n_dof=10, harmonics=5, support=0), 10**6)
    >>> check(SolveMemory(n_dof=10**6, harmonics=10**4, support=0), 10**9)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rheolin.budget.MemoryBudgetError: the harmonic-balance solve needs an estimated 1.28e+03 GB ...
    """
    memory.fit(budget)
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
