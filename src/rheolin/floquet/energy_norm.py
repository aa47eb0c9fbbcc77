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

__all__ = ["MU_FACTOR", "definite_factor", "energy_weight", "norm_in", "positive_definite"]

#: The energy norm ``S = K_s + mu M_s`` starts from ``mu = (MU_FACTOR * radius)^2``, ``radius``
#: the band's: the modes below it are weighed by their kinetic energy, those above by their
#: strain energy (on the 2,610-DOF gearbox ``(1e4 rad/s)^2`` bounded the loop at 0.88 and
#: ``(1e6 rad/s)^2`` at 1.13 where the band's radius, 8e4 rad/s, gave 0.68).
MU_FACTOR = 1.0

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


def energy_weight(K: Any, M: Any, radius: float) -> tuple[sp.csc_array, Any] | None:
    """The norm the small-gain loop is measured in: ``||x||_S^2 = x^H S x`` with
    ``S = K_s + mu M_s`` (``K_s``, ``M_s`` the Hermitian parts of the time-averaged ``K``,
    ``M``), ``mu = (MU_FACTOR radius)^2`` raised by decades until ``S`` is positive definite;
    ``(S, a function solving with S)``, or None when no ``mu`` up to ``1e8`` times that makes
    it so.

    The modes below ``radius`` (the band's) are weighed by their kinetic energy at that
    frequency, those above by their strain energy: the loop ``G_C(s) E_k`` of a shaft whose
    stiffness or mass varies by a fraction ``eps`` of itself then has a gain of about
    ``eps`` whatever the mesh, where in the Euclidean norm of the DOFs it grows with the
    stiffness ratio of the mesh (docs/stability.md, 8.3)."""
    K, M = sp.csc_array(K), sp.csc_array(M)
    Ks, Ms = ((X + X.conj().T) / 2 for X in (K, M))
    if not (np.iscomplexobj(Ks.data) or np.iscomplexobj(Ms.data)):
        Ks, Ms = Ks.real, Ms.real
    mu = (MU_FACTOR * max(float(radius), 1e-300)) ** 2
    for _ in range(9):
        S = sp.csc_array(Ks + mu * Ms)
        lu = definite_factor(S)
        if lu is not None:
            return S, _solver(lu, np.iscomplexobj(S.data))
        mu *= 10.0
    return None


def _solver(lu: Any, complex_factor: bool) -> Any:
    """``b -> lu.solve(b)``, complex right-hand sides included with a real factor."""

    def solve(b: np.ndarray) -> np.ndarray:
        if np.iscomplexobj(b) and not complex_factor:
            re = np.asarray(lu.solve(np.ascontiguousarray(b.real)))
            return re + 1j * np.asarray(lu.solve(np.ascontiguousarray(b.imag)))
        return np.asarray(lu.solve(b))

    return solve


def norm_in(
    apply: Any, adjoint: Any, S: Any, solve: Any, dim: int, rng: np.random.Generator
) -> float:
    """The norm of an operator in ``||x||_S = sqrt(x^H S x)``: the largest eigenvalue of
    ``A^H S A x = mu S x`` by Lanczos (ARPACK, relative tolerance 1e-6), square-rooted. Where
    ARPACK does not converge, the power iteration's estimate (from below) times 1.05."""
    A = spla.LinearOperator((dim, dim), matvec=lambda x: adjoint(S @ apply(x)), dtype=complex)
    Sop = spla.LinearOperator((dim, dim), matvec=lambda x: S @ x, dtype=complex)
    Sinv = spla.LinearOperator((dim, dim), matvec=solve, dtype=complex)
    v0 = rng.standard_normal(dim) + 1j * rng.standard_normal(dim)
    try:
        mu = spla.eigsh(
            A, k=1, M=Sop, Minv=Sinv, which="LA", tol=1e-6, v0=v0, ncv=min(dim, 16),
            maxiter=40, return_eigenvectors=False,
        )  # fmt: skip
        return float(np.sqrt(max(float(mu[-1]), 0.0)))
    except spla.ArpackNoConvergence:
        pass
    x = v0 / np.sqrt(abs(np.vdot(v0, S @ v0)))
    value = value_new = 0.0
    for _ in range(NORM_STEPS):
        y = apply(x)
        value_new = float(np.sqrt(abs(np.vdot(y, S @ y))))
        z = solve(adjoint(S @ y))
        nz = float(np.sqrt(abs(np.vdot(z, S @ z))))
        if nz == 0 or value_new == 0:
            return value_new
        x = z / nz
        if abs(value_new - value) <= 1e-3 * value_new:
            break
        value = value_new
    return 1.05 * value_new
