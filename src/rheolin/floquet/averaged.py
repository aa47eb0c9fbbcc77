"""The time-averaged modes a lattice search starts from, and the memory a lattice search needs."""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..harmonics.blocks import coefficient_blocks
from ..harmonics.hill import _dense, state_scaling
from ..harmonics.lattice import Lattice
from ..system.periodic import PeriodicSystem
from .result import _EPS

__all__ = ["LU_FILL", "MAX_AVERAGED_DENSE", "lattice_memory"]


#: Dense eigen-decomposition of the time-averaged pencil up to this size (``2 n``).
MAX_AVERAGED_DENSE = 4000


#: Below this condition number of the balanced ``B`` the pencil is reduced to the standard
#: problem ``B^-1 A`` (5x faster than QZ on the gearbox, 252 x 252: 0.05 s against 0.25 s);
#: above it (massless DOFs: ``B`` singular) QZ keeps the infinite eigenvalues apart.
STANDARD_COND = 1e6


#: Estimated LU fill of the lattice operator (entries of the factors / entries of ``Q``).
LU_FILL = 12.0


class _Averaged:
    """Eigen-decomposition of the time-averaged balanced pencil (first-order, ``2 n``)."""

    def __init__(self, system: PeriodicSystem) -> None:
        n = system.n
        if 2 * n > MAX_AVERAGED_DENSE:
            raise ValueError(
                f"the lattice Floquet method needs the modes of the time-averaged system "
                f"densely (2 n = {2 * n} > {MAX_AVERAGED_DENSE}); reduce the model "
                "(condensed bodies) or give a dense harmonic set with method='sparse'"
            )
        self.sq, self.sv = sq, sv = state_scaling(system)
        Ad, Bd, Ms = _averaged_pencil(system, sq, sv)
        # cond(B) from the balanced mass block (B = diag(I, M))
        mu = np.linalg.svd(Ms, compute_uv=False) if n else np.ones(1)
        hi, lo = max(float(mu.max()), 1.0), min(float(mu.min()), 1.0)
        known = system.kept("averaged_decomposition")
        if known is not None and lo > 0 and hi / lo <= STANDARD_COND and Ad.dtype == float:
            lam, X, W = _from_modal(known, sq, sv)
        elif lo > 0 and hi / lo <= STANDARD_COND:
            # B^-1 A by blocks (B = diag(I, M)); left vectors of the pencil from those of
            # B^-1 A: w^H B^-1 A = lam w^H B^-1
            C = Ad.copy()
            C[n:] = np.linalg.solve(Ms, Ad[n:])
            lam, Y, X = sla.eig(C, left=True, right=True, check_finite=False, overwrite_a=True)
            W = np.array(Y, dtype=complex)
            W[n:] = np.linalg.solve(Ms.conj().T, W[n:])
        else:
            lam, W, X = sla.eig(Ad, Bd, left=True, right=True, check_finite=False)
        finite = np.isfinite(lam)
        self.lam = lam[finite]
        X, W = X[:, finite], W[:, finite]
        X = X / np.linalg.norm(X, axis=0)
        d = np.einsum("ij,ij->j", W.conj(), Bd @ X)
        ok = np.abs(d) > 1e3 * _EPS * np.linalg.norm(W, axis=0)
        self.W = W / np.where(ok, d, 1.0).conj()
        self.X = X
        self.WB = self.W.conj().T @ Bd  # modal coordinates of a balanced vector: WB @ y
        # first-order rounding bound of each averaged exponent (huge in a Jordan block, such
        # as the double zero of a free rotation): copies of it scatter by as much
        normA, normB = np.linalg.norm(Ad, 1), np.linalg.norm(Bd, 1)
        cond = np.linalg.norm(self.W, axis=0) / np.maximum(np.abs(d), np.finfo(float).tiny)
        self.bound = _EPS * (normA + np.abs(self.lam) * normB) * np.where(ok, cond, np.inf)
        self.modal = bool(ok.all()) and self.lam.size == 2 * n
        self.n = n


def _from_modal(
    known: tuple[np.ndarray, ...], sq: np.ndarray, sv: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eigenvalues, right and left eigenvectors of the balanced pencil from the decomposition
    a modal solve made of the same time-averaged system (:class:`rheolin.linalg.ModalInverse`:
    ``H = V diag(lam) V^-1`` in ``x = (L_K^T q, L_M^T v)``), without a second eigenvalue
    problem (13 ms of the gearbox's verdict per speed).

    The balanced state ``y = (S_q q, S_v v) = T x`` with ``T = diag(S_q L_K^-T, S_v L_M^-T)``
    has ``B^-1 A = T H T^-1``: right vectors ``T V``, left ones (of ``B^-1 A``) the rows of
    ``V^-1 T^-1``, and the pencil's ``w^H = y^H B^-1`` with ``B^-1 = diag(I, S_v M^-1 S_v)``,
    i.e. ``W^H = [V^-1_q L_K^T S_q^-1, V^-1_v L_M^-1 S_v]``.
    """
    lam, V, Vi, Lk, LkTi, Lmi = known
    n = sq.size
    X = np.concatenate([sq[:, None] * (LkTi @ V[:n]), sv[:, None] * (Lmi.T @ V[n:])])
    WH = np.concatenate([(Vi[:, :n] @ Lk.T) / sq[None, :], (Vi[:, n:] @ Lmi) * sv[None, :]], axis=1)
    return lam, X, WH.conj().T


def _averaged_pencil(
    system: PeriodicSystem, sq: np.ndarray, sv: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The balanced time-averaged pencil ``(A, B)`` of :func:`rheolin.harmonics.hill.hill_pencil` on
    harmonic 0, dense, and its mass block: ``A = [[0, S_q S_v^-1], [-K, -D]]``,
    ``B = diag(I, M)`` with ``K = S_v^-1 K_0 S_q^-1``, ``D = S_v^-1 D_0 S_v^-1``,
    ``M = S_v^-1 M_0 S_v^-1``."""
    n = system.n

    def dense(table: dict, right: np.ndarray) -> np.ndarray:
        x = table.get(0)
        return np.zeros((n, n)) if x is None else _dense(x) / sv[:, None] / right[None, :]

    Ks, Ds, Ms = dense(system.K, sq), dense(system.D, sv), dense(system.M, sv)
    # real coefficients (the usual case): a real eigenproblem, whose complex exponents come
    # in exact conjugate pairs
    dtype = np.result_type(Ks, Ds, Ms, float)
    A = np.zeros((2 * n, 2 * n), dtype=dtype)
    B = np.zeros((2 * n, 2 * n), dtype=dtype)
    A[np.arange(n), n + np.arange(n)] = sq / sv
    A[n:, :n] = -Ks
    A[n:, n:] = -Ds
    B[np.arange(n), np.arange(n)] = 1.0
    B[n:, n:] = Ms
    return A, B, Ms


def lattice_memory(system: PeriodicSystem, lattice: Lattice, k: int = 8) -> int:
    """Estimated peak memory [bytes] of :func:`lattice_exponents` on ``lattice``.

    Counted without building anything: the entries of the lattice operator (from the block
    patterns and the number of harmonic pairs each coefficient harmonic couples), its LU at
    :data:`LU_FILL` times those entries, the Arnoldi basis, and the dense averaged modes.
    """
    H = lattice.indices
    n = system.n
    nnz = 0
    for k_h, block in coefficient_blocks(system).items():
        pos = np.minimum(np.searchsorted(H, H + k_h), H.size - 1)
        pairs = int(np.count_nonzero(H[pos] == H + k_h))
        if not pairs:
            continue
        nnz += pairs * int(block.entries()[0].size)
    from .search import ARNOLDI_STEPS

    size2 = 2 * n * H.size
    ncv = max(2 * k + 1, ARNOLDI_STEPS[-1] + 1)  # the Arnoldi basis (no restarts)
    return int(
        nnz * 16 * (6 + LU_FILL) + size2 * 16 * (ncv + 8) + (2 * n) ** 2 * 16 * 6 + 64 * 2**20
    )
