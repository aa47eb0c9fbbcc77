"""``A0(n)^-1`` from one eigendecomposition of the time-averaged pencil (modal resolvent).

With ``x = [L_K^T q; L_M^T q']`` (``M_0 = L_M L_M^T`` and ``K_s + sigma M_0 = L_K L_K^T``,
Cholesky factors of the mass and of the symmetric part of the stiffness, shifted when that is
not positive definite) the equations ``M q'' + D q' + K q = f`` become ``x' = H x + B f`` with

    H = [[0, L_K^T L_M^-T], [-L_M^-1 K L_K^-T, -L_M^-1 D L_M^-T]],   B = [0; L_M^-1].

For a conservative system ``H`` is skew-symmetric, so its eigenvectors are orthogonal; light
damping, gyroscopic and circulatory terms keep them well conditioned (measured cond(V) = 3.9
on the embedded gearbox, against 1.7e8 in the unscaled companion form). With
``H = V diag(lambda) V^-1``,

    A0(n)^-1 = Phi diag(1 / (s_n - lambda)) Psi,  Phi = L_K^-T V[:N],  Psi = V^-1[:, N:] L_M^-1,

so applying it to every harmonic at once is two matrix products shared by all harmonics and a
scaling: no factorization per harmonic. The decomposition costs ``O((2N)^3)`` once, worth it
when the harmonics outnumber ``~N / 10``. Its accuracy is measured on probe harmonics before
use (``ModalUnavailable`` otherwise: a singular mass, a defective pencil such as free
rigid-body modes); :meth:`ModalInverse.solve` adds one step of iterative refinement.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.linalg as sla

from .errors import SingularBlockError
from .pencil import Pencil

__all__ = ["ModalInverse", "ModalUnavailable"]

#: Largest relative residual ``||A0 x - b|| / ||b||`` of the unrefined modal solve accepted.
PROBE_RTOL = 1e-11
#: Probe harmonics: this many spread over the set plus as many nearest the resonances.
_PROBES = 8


class ModalUnavailable(RuntimeError):
    """The modal resolvent is not accurate for this pencil (use a factorization)."""


def _cholesky(A: np.ndarray) -> np.ndarray | None:
    try:
        return np.asarray(sla.cholesky(A, lower=True, check_finite=False))
    except np.linalg.LinAlgError:
        return None


class ModalInverse:
    """``A0(n)^-1`` for the harmonics ``ns`` by the modal resolvent (see the module)."""

    name = "modal"
    exact = False

    def __init__(self, pencil: Pencil, ns: np.ndarray) -> None:
        self.pencil, self.ns = pencil, np.asarray(ns)
        K, D, M = pencil.dense()
        N = pencil.n
        Lm = _cholesky(M)
        if Lm is None:
            raise ModalUnavailable("the mean mass matrix is not positive definite")
        Ks = 0.5 * (K + K.T)
        rho = max(float(np.trace(Ks)) / float(np.trace(M)), 1.0)
        Lk = None
        for sigma in (0.0, 1e-6 * rho, 1e-3 * rho, rho):
            Lk = _cholesky(Ks + sigma * M)
            if Lk is not None:
                break
        if Lk is None:
            raise ModalUnavailable("no positive definite scaling of the mean stiffness")
        I = np.eye(N)
        LkTi = sla.solve_triangular(Lk, I, lower=True, check_finite=False).T  # L_K^-T
        Lmi = sla.solve_triangular(Lm, I, lower=True, check_finite=False)  # L_M^-1
        H = np.block([[np.zeros((N, N)), Lk.T @ Lmi.T], [-Lmi @ K @ LkTi, -Lmi @ D @ Lmi.T]])
        lam, V = sla.eig(H, overwrite_a=True, check_finite=False)
        try:
            Vi = sla.lu_solve(sla.lu_factor(V, check_finite=False), np.eye(2 * N))
        except (np.linalg.LinAlgError, ValueError):
            raise ModalUnavailable("defective pencil (singular eigenvector matrix)") from None
        if not (np.all(np.isfinite(lam)) and np.all(np.isfinite(Vi))):
            raise ModalUnavailable("non-finite eigen-decomposition")
        self.lam = lam
        #: ``(lam, V, V^-1, L_K, L_K^-T, L_M^-1)``: the decomposition in the coordinates above
        #: (the lattice Floquet method takes its time-averaged modes from it, see
        #: :class:`rheolin.floquet.averaged.Averaged`)
        self.decomposition = (lam, V, Vi, Lk, LkTi, Lmi)
        self._PhiT = np.ascontiguousarray((LkTi @ V[:N]).T)  # (2N, N)
        self._PsiT = np.ascontiguousarray((Vi[:, N:] @ Lmi).T)  # (N, 2N)
        gap = pencil.s(self.ns)[:, None] - lam[None, :]
        scale = np.maximum(np.abs(lam), np.abs(pencil.s(self.ns))[:, None])
        singular = np.abs(gap) <= 1e3 * np.finfo(float).eps * scale
        if singular.any():
            i = int(np.flatnonzero(singular.any(axis=1))[0])
            raise SingularBlockError(int(self.ns[i]), "an undamped eigenvalue at this harmonic")
        self._scale = 1.0 / gap  # (|H+|, 2N)
        self.probe_error = self._probe()
        if not self.probe_error <= PROBE_RTOL:
            raise ModalUnavailable(f"modal solve error {self.probe_error:.2g} on probe harmonics")

    def _probe(self) -> float:
        """Largest relative residual of the unrefined solve over probe harmonics."""
        h = self.ns.size
        spread = np.linspace(0, h - 1, min(h, _PROBES)).astype(int)
        nearest = np.argsort(np.abs(self._scale).max(axis=1))[-_PROBES:]
        idx = np.unique(np.concatenate([spread, nearest]))
        rng = np.random.default_rng(self.pencil.n)
        B = rng.standard_normal((idx.size, self.pencil.n)) + 0j
        X = self._apply(B, idx)
        R = B - self.pencil.apply(X, self.ns[idx])
        return float(np.max(np.linalg.norm(R, axis=1) / np.linalg.norm(B, axis=1)))

    def _apply(self, R: np.ndarray, idx: np.ndarray) -> np.ndarray:
        return np.asarray(((R @ self._PsiT) * self._scale[idx]) @ self._PhiT)

    def solve(self, R: np.ndarray) -> np.ndarray:
        """``A0(n)^-1 r_n`` for every row of ``R`` (one refinement step); zero rows stay zero."""
        out = np.zeros_like(R, dtype=complex)
        idx = np.flatnonzero(np.any(R != 0, axis=1))
        if idx.size:
            B = R[idx].astype(complex)
            X = self._apply(B, idx)
            X += self._apply(B - self.pencil.apply(X, self.ns[idx]), idx)
            out[idx] = X
        return out

    def restricted(self, rows: np.ndarray, cols: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
        """``Z -> (A0(n)^-1[rows, cols] z_n)_n``: two products shared by every harmonic."""
        PsiT = np.ascontiguousarray(self._PsiT[cols])  # (|cols|, 2N)
        PhiT = np.ascontiguousarray(self._PhiT[:, rows])  # (2N, |rows|)
        scale = self._scale
        return lambda Z: ((Z @ PsiT) * scale) @ PhiT
