"""The energy norm in which the small-gain loop of a band's modes left out is measured
(docs/stability.md, 8.3), and the sparse definiteness test it shares with the energy bound.

>>> import numpy as np, scipy.sparse as sp
>>> S, solve = energy_weight(sp.diags_array([4.0, 9.0]), sp.identity(2), 1.0)
>>> S.toarray().diagonal().tolist(), solve(np.array([5.0, 10.0])).tolist()
([5.0, 10.0], [1.0, 1.0])
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = [
    "MU_FACTOR",
    "NORM_TOL",
    "SAME_INPUT",
    "EnergyFamily",
    "apply_norm",
    "column_energies",
    "definite_factor",
    "energy_weight",
    "norm_in",
    "positive_definite",
]

#: The energy norm ``S = K_s + mu M_s`` starts from ``mu = (MU_FACTOR * radius)^2``, ``radius``
#: the band's: the modes below it are weighed by their kinetic energy, those above by their
#: strain energy (on the 2,610-DOF gearbox ``(1e4 rad/s)^2`` bounded the loop at 0.88 and
#: ``(1e6 rad/s)^2`` at 1.13 where the band's radius, 8e4 rad/s, gave 0.68).
MU_FACTOR = 1.0

#: ARPACK's relative residual for a loop's norm. The Ritz value's error is of the order of
#: the residual squared over the gap: far below 1e-4 of the norm. At 1e-6, ARPACK ran out of
#: its 40 restarts in the kinetic norms of the high frequencies (1.2e6 to 3e6 rad/s on the
#: 2,610-DOF gearbox, 0.8 s a point, the power iteration's estimate kept), where the top of
#: the flat shaft's loop is a tight cluster; at 1e-4 it converged there to the same value
#: within 2e-6 whatever its basis (16 or 32 vectors).
NORM_TOL = 1e-4

#: An input norm ``N(omega_hi)`` is replaced by the smaller ``mu / (mu + omega_hi^2) S``,
#: which reuses the factor of ``S``, while ``omega_hi^2 <= SAME_INPUT mu``: the loop's bound
#: then loses at most 2.5 % (``sqrt(1 + SAME_INPUT)``), and the point saves a sparse factor
#: and its block solves.
SAME_INPUT = 0.05

#: Power-iteration steps for the norm where Lanczos does not converge.
NORM_STEPS = 12


def definite_factor(A: Any) -> Any:
    """The SuperLU factor of the Hermitian sparse ``A`` with symmetric (diagonal) pivots when
    ``A`` is positive definite (every pivot positive: Sylvester's law of inertia), else None."""
    A = sp.csc_array(A)
    try:
        lu = spla.splu(
            A,
            permc_spec="MMD_AT_PLUS_A",
            diag_pivot_thresh=0.0,
            options={"SymmetricMode": True},
        )
    except RuntimeError:  # exactly singular
        return None
    if not np.array_equal(lu.perm_r, lu.perm_c):
        return None  # an off-diagonal pivot: not the LDL^H of a definite matrix
    d = lu.U.diagonal()
    ok = np.all(d.real > 0) and np.all(np.abs(d.imag) <= 1e-10 * np.abs(d.real))
    return lu if ok else None


def positive_definite(A: Any) -> bool:
    """True when the Hermitian sparse ``A`` is positive definite (:func:`definite_factor`)."""
    return definite_factor(A) is not None


class EnergyFamily:
    """The energy norms of the frequency scan (docs/stability.md, 8.3): at frequency
    ``omega``

        N(omega) = mu / (mu + omega^2) (S + omega^2 M_s),   S = K_s + mu M_s,

    which is ``S`` at low frequency and tends to the kinetic ``mu M_s`` far above
    ``sqrt(mu)`` (the band's radius): a mode far above the band is no longer weighed by a
    strain energy that grows with the mesh. ``N(omega) = F(i omega)^H F(i omega)`` with
    ``F(s) = (I + s L^1/2) V^-1 / (1 + s / sqrt(mu))`` (``V^T S V = I``, ``V^T M_s V = L``),
    analytic, bounded and invertible for ``Re s >= 0``, and ``||F(s) x||^2 >= mu x^H M_s x``
    there: the small-gain argument holds with the norm ``||F(s_n) q_n||`` of each harmonic.

    ``N`` decreases with ``omega`` (every Rayleigh quotient of ``S`` over ``M_s`` is at
    least ``mu``), so ``N(omega_hi)`` is the smallest of the norms at
    ``|omega'| <= omega_hi``, and ``mu M_s = N(infinity)`` the smallest of all. Where
    ``M_s`` is not positive definite (a DOF without mass) the norm is ``S`` at every
    frequency (``varying`` False).

    >>> import numpy as np, scipy.sparse as sp
    >>> f = EnergyFamily(sp.diags_array([4.0, 9.0]), sp.identity(2), 1.0)
    >>> f.mu, f.output(0.0).diagonal().tolist(), f.output(1e6).diagonal().round(6).tolist()
    (1.0, [5.0, 10.0], [1.0, 1.0])
    """

    def __init__(self, K: Any, M: Any, radius: float) -> None:
        K, M = sp.csc_array(K), sp.csc_array(M)
        Ks, Ms = ((X + X.conj().T) / 2 for X in (K, M))
        if not (np.iscomplexobj(Ks.data) or np.iscomplexobj(Ms.data)):
            Ks, Ms = Ks.real, Ms.real
        self.Ks, self.Ms = sp.csc_array(Ks), sp.csc_array(Ms)
        self.mu = (MU_FACTOR * max(float(radius), 1e-300)) ** 2
        self.S: sp.csc_array | None = None
        self.solve: Any = None
        for _ in range(9):
            S = sp.csc_array(self.Ks + self.mu * self.Ms)
            lu = definite_factor(S)
            if lu is not None:
                self.S, self.solve = S, _solver(lu, np.iscomplexobj(S.data))
                break
            self.mu *= 10.0
        # the kinetic limit mu M_s: its factor gives the dual norms (None: a DOF without
        # mass, where the norm does not vary)
        mass = definite_factor(self.Ms) if self.S is not None else None
        self.mass_solve: Any = (
            None if mass is None else _solver(mass, np.iscomplexobj(self.Ms.data))
        )

    @property
    def definite(self) -> bool:
        """``S`` is positive definite (else no energy norm)."""
        return self.S is not None

    @property
    def varying(self) -> bool:
        """The norm follows the frequency (``M_s`` is positive definite)."""
        return self.S is not None and self.mass_solve is not None

    def output(self, omega: float) -> sp.csc_array:
        """``N(omega)``."""
        assert self.S is not None
        if not self.varying:
            return self.S
        w2 = float(omega) ** 2
        with np.errstate(under="ignore"):  # tiny entries of a scaled norm are zeros
            return sp.csc_array((self.S + w2 * self.Ms) * (self.mu / (self.mu + w2)))

    def alpha(self, omega: float) -> float:
        """``mu / (mu + omega^2)``: ``alpha(omega) S`` is no larger than ``N(omega)`` (1 when
        the norm does not vary)."""
        if not self.varying:
            return 1.0
        return self.mu / (self.mu + float(omega) ** 2)

    def scaled(self, omega: float) -> tuple[sp.csc_array, Any]:
        """``alpha(omega) S`` and a solve with it (the factor of ``S``): no larger than
        ``N(omega)``, and close to it while ``omega^2`` is small against ``mu``."""
        assert self.S is not None
        a, solve = self.alpha(omega), self.solve
        if a == 1.0:
            return self.S, solve
        with np.errstate(under="ignore"):
            return sp.csc_array(a * self.S), _divided(solve, a)

    def input(self, omega_hi: float) -> tuple[sp.csc_array, Any]:
        """A norm no larger than ``N(omega')`` for every ``|omega'| <= omega_hi``, and a
        solve with it: ``N(omega_hi)`` (one sparse factor), or ``alpha(omega_hi) S`` while
        ``omega_hi^2 <= SAME_INPUT mu``."""
        assert self.S is not None
        if not self.varying:
            return self.S, self.solve
        w2 = float(omega_hi) ** 2
        if w2 <= SAME_INPUT * self.mu:
            return self.scaled(omega_hi)
        A = sp.csc_array(self.S + w2 * self.Ms)
        lu = definite_factor(A)
        if lu is None:  # rounding: the smaller alpha S
            return self.scaled(omega_hi)
        alpha = self.alpha(omega_hi)
        with np.errstate(under="ignore"):
            return sp.csc_array(alpha * A), _divided(_solver(lu, np.iscomplexobj(A.data)), alpha)

    def dual_solve(self) -> Any:
        """A solve with the smallest norm of the family (``mu M_s``, the kinetic limit; ``S``
        when the norm does not vary): the dual norms ``sqrt(f^H N^-1 f)`` at every frequency
        are at most those it gives."""
        if not self.varying:
            return self.solve
        return _divided(self.mass_solve, self.mu)


def _divided(solve: Any, a: float) -> Any:
    """``b -> solve(b) / a`` (entries that underflow are zeros)."""

    def divided(b: np.ndarray) -> np.ndarray:
        x = solve(b)
        with np.errstate(under="ignore"):
            return np.asarray(x / a)

    return divided


def energy_weight(K: Any, M: Any, radius: float) -> tuple[sp.csc_array, Any] | None:
    """The energy norm ``||x||_S^2 = x^H S x`` with ``S = K_s + mu M_s`` (``K_s``, ``M_s``
    the Hermitian parts of the time-averaged ``K``, ``M``), ``mu = (MU_FACTOR radius)^2``
    raised by decades until ``S`` is positive definite: ``(S, a function solving with S)``,
    or None when no ``mu`` up to ``1e8`` times that makes it so. It is the low-frequency
    norm of :class:`EnergyFamily`, which the scan measures its loops in: the modes below
    ``radius`` (the band's) weighed by their kinetic energy at that frequency, those above
    by their strain energy (docs/stability.md, 8.3)."""
    family = EnergyFamily(K, M, radius)
    return (family.S, family.solve) if family.definite else None


def _solver(lu: Any, complex_factor: bool) -> Any:
    """``b -> lu.solve(b)``, complex right-hand sides included with a real factor."""

    def solve(b: np.ndarray) -> np.ndarray:
        if np.iscomplexobj(b) and not complex_factor:
            re = np.asarray(lu.solve(np.ascontiguousarray(b.real)))
            return re + 1j * np.asarray(lu.solve(np.ascontiguousarray(b.imag)))
        return np.asarray(lu.solve(b))

    return solve


def apply_norm(S: Any, Z: np.ndarray) -> np.ndarray:
    """``S @ Z`` for a block ``Z`` of complex columns; a real ``S`` is applied to the real
    and imaginary parts as one real block (no complex copy of ``S``, a quarter of the
    multiplications).

    >>> import numpy as np, scipy.sparse as sp
    >>> apply_norm(sp.diags_array([2.0, 3.0]), np.array([[1 + 1j], [2j]])).ravel().tolist()
    [(2+2j), 6j]
    """
    Z = np.asarray(Z)
    if not (np.iscomplexobj(Z) and Z.ndim == 2) or np.iscomplexobj(getattr(S, "data", 1j)):
        return np.asarray(S @ Z)
    Zf = np.ascontiguousarray(Z).view(np.float64)  # columns (re, im) side by side
    return np.ascontiguousarray(S @ Zf).view(np.complex128)


def column_energies(S: Any, Z: np.ndarray) -> np.ndarray:
    """``Re z_m^H S z_m`` for every column ``z_m`` of ``Z`` (``S`` Hermitian).

    >>> import numpy as np, scipy.sparse as sp
    >>> column_energies(sp.diags_array([2.0, 3.0]), np.array([[1 + 1j, 1], [2j, 0]])).tolist()
    [16.0, 2.0]
    """
    Z = np.asarray(Z)
    SZ = apply_norm(S, Z)
    return np.asarray(np.sum(Z.real * SZ.real + Z.imag * SZ.imag, axis=0))


def norm_in(
    apply: Any,
    adjoint: Any,
    S: Any,
    solve: Any,
    dim: int,
    rng: np.random.Generator,
    S_in: Any = None,
) -> float:
    """The norm of an operator from ``||x||_S_in`` to ``||y||_S = sqrt(y^H S y)`` (``S_in``
    default ``S``; ``solve`` solves with ``S_in``): the largest eigenvalue of
    ``A^H S A x = mu S_in x`` by Lanczos (ARPACK, relative residual :data:`NORM_TOL`),
    square-rooted. Where ARPACK does not converge, the power iteration's estimate (from
    below) times 1.05."""
    Sin = S if S_in is None else S_in
    A = spla.LinearOperator((dim, dim), matvec=lambda x: adjoint(S @ apply(x)), dtype=complex)
    Sop = spla.LinearOperator((dim, dim), matvec=lambda x: Sin @ x, dtype=complex)
    Sinv = spla.LinearOperator((dim, dim), matvec=solve, dtype=complex)
    v0 = rng.standard_normal(dim) + 1j * rng.standard_normal(dim)
    try:
        mu = spla.eigsh(
            A, k=1, M=Sop, Minv=Sinv, which="LA", tol=NORM_TOL, v0=v0, ncv=min(dim, 16),
            maxiter=40, return_eigenvectors=False,
        )  # fmt: skip
        return float(np.sqrt(max(float(mu[-1]), 0.0)))
    except spla.ArpackNoConvergence:
        pass
    x = v0 / np.sqrt(abs(np.vdot(v0, Sin @ v0)))
    value = value_new = 0.0
    for _ in range(NORM_STEPS):
        y = apply(x)
        value_new = float(np.sqrt(abs(np.vdot(y, S @ y))))
        z = solve(adjoint(S @ y))
        nz = float(np.sqrt(abs(np.vdot(z, Sin @ z))))
        if nz == 0 or value_new == 0:
            return value_new
        x = z / nz
        if abs(value_new - value) <= 1e-3 * value_new:
            break
        value = value_new
    return 1.05 * value_new
