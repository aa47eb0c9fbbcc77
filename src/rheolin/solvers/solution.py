"""One result type for every steady-state method."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["STATUS", "Solution"]

#: Meaning of :attr:`Solution.status`.
STATUS = {
    0: "converged",
    1: "iteration limit reached before the tolerance",
    2: "diverged",
    3: "singular or ill-conditioned system",
    4: "converged, but the operating point is unstable (the steady state is not physical)",
}


@dataclass
class Solution:
    """Periodic steady state ``q(t) = sum_n q_n exp(i n omega t)``.

    Attributes
    ----------
    harmonics
        Harmonic indices ``n`` (sorted, symmetric).
    q
        Complex coefficients, shape ``(len(harmonics), n_dof)``; ``q[-n] = conj(q[n])``.
    omega
        Base angular frequency ``w1`` [rad/s].
    success, status, message
        Whether the requested tolerance was met; a code from :data:`STATUS`; an explanation.
    method
        The method that produced ``q`` (for ``auto``, the one finally used).
    iterations
        Iterations of the iterative method (0 for ``lti`` and ``direct``).
    history
        Relative residual per iteration.
    residual
        ``||f - A q|| / ||f||`` of the coupled truncated system, computed by applying the
        harmonic-balance operator (not the method's own estimate).
    stable
        Floquet stability of the operating point (None when it was not checked).
    max_floquet_real
        Largest real part of the Floquet exponents [1/s] (None when not checked).
    floquet
        The :class:`~rheolin.FloquetResult` of the stability check (None when not checked).
    """

    harmonics: np.ndarray
    q: np.ndarray
    omega: float
    success: bool
    status: int
    message: str
    method: str
    iterations: int = 0
    history: list[float] = field(default_factory=list)
    residual: float = float("nan")
    stable: bool | None = None
    max_floquet_real: float | None = None
    info: dict = field(default_factory=dict)
    floquet: Any = None

    @property
    def frequencies(self) -> np.ndarray:
        """Physical frequency of each harmonic [Hz]: ``n omega / (2 pi)``."""
        return self.harmonics * self.omega / (2.0 * np.pi)

    def harmonic(self, n: int) -> np.ndarray:
        """``q_n``; raises KeyError if ``n`` is not in the harmonic set."""
        hit = np.flatnonzero(self.harmonics == n)
        if hit.size == 0:
            raise KeyError(f"harmonic {n} is not in the solution's harmonic set")
        return self.q[hit[0]]

    def evaluate(self, t: float | np.ndarray) -> np.ndarray:
        """Real response ``q(t)`` at times ``t``, shape ``(len(t), n_dof)``."""
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        phase = np.exp(1j * self.omega * np.outer(tt, self.harmonics))
        return (phase @ self.q).real

    def __repr__(self) -> str:
        return (
            f"Solution(method={self.method!r}, success={self.success}, status={self.status}, "
            f"iterations={self.iterations}, residual={self.residual:.3e}, stable={self.stable}, "
            f"harmonics={len(self.harmonics)}, n_dof={self.q.shape[1]}, "
            f"message={self.message!r})"
        )
