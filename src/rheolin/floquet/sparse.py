"""Sparse Hill path: the exponents near the imaginary axis by shift-invert Arnoldi along a
frequency range.
"""

from __future__ import annotations

import logging
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..harmonics.hill import hill_pencil
from ..harmonics.sets import HarmonicSet
from ..system.periodic import PeriodicSystem
from .common import edge_weight, error_bound, fold, grid_representatives, harmonic_energy
from .result import FloquetResult, floquet_result

__all__ = []

log = logging.getLogger(__name__)


# ----------------------------------------------------------------------------- sparse
def _shift_invert(
    A: sp.csc_array, B: sp.csc_array, sigma: complex, k: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``k`` eigenvalues of ``lambda B x = A x`` nearest ``sigma`` with right and left vectors."""
    size = A.shape[0]
    lu = spla.splu(sp.csc_array(A - sigma * B), permc_spec="MMD_ATA")
    op = spla.LinearOperator(
        (size, size), matvec=lambda x: lu.solve(np.asarray(B @ x)), dtype=complex
    )
    opH = spla.LinearOperator(
        (size, size),
        matvec=lambda x: np.asarray(B.conj().T @ lu.solve(np.asarray(x), trans="H")),
        dtype=complex,
    )
    kk = min(k, size - 2)
    nu, x = spla.eigs(op, k=kk, which="LM", tol=1e-13)
    mu, wl = spla.eigs(opH, k=kk, which="LM", tol=1e-13)
    lam = sigma + 1.0 / nu
    # left eigenvectors: y = (A - sigma B)^-H w, matched to the right ones by eigenvalue
    y_all = np.column_stack([lu.solve(wl[:, j], trans="H") for j in range(kk)])
    lam_left = sigma + 1.0 / np.conj(mu)
    match = np.argmin(np.abs(lam[:, None] - lam_left[None, :]), axis=1)
    return lam, x, y_all[:, match]


def floquet_sparse(
    system: PeriodicSystem,
    hset: HarmonicSet,
    frequencies: tuple[float, float] | None,
    k: int,
    max_shifts: int,
) -> FloquetResult:
    t0 = time.perf_counter()
    A, B = hill_pencil(system, hset)
    H = hset.indices
    n, w = system.n, system.omega
    lo, hi = frequencies if frequencies is not None else (0.0, max(abs(H).max() * w / 2, w))
    if not 0.0 <= lo < hi:
        raise ValueError(f"`frequencies` must be (lo, hi) with 0 <= lo < hi, got {frequencies!r}")
    normA, normB = spla.norm(A, 1), spla.norm(B, 1)
    lams: list[np.ndarray] = []
    xs: list[np.ndarray] = []
    ys: list[np.ndarray] = []
    disks: list[tuple[complex, float]] = []
    omega = lo
    alpha = 1e-4 * w
    while omega <= hi and len(disks) < max_shifts:
        sigma = alpha + 1j * omega
        try:
            lam, x, y = _shift_invert(A, B, sigma, k)
        except RuntimeError:  # exactly singular: move the shift slightly
            sigma += 1e-3 * w * (1 + 1j)
            lam, x, y = _shift_invert(A, B, sigma, k)
        radius = float(np.abs(lam - sigma).max())
        disks.append((sigma, radius))
        lams.append(lam)
        xs.append(x)
        ys.append(y)
        omega = sigma.imag + max(radius, (hi - lo) / max_shifts)
    lam = np.concatenate(lams)
    x, y = np.hstack(xs), np.hstack(ys)
    per_h = harmonic_energy(x, H.size, n)
    centroid = np.abs(H).astype(float) @ per_h
    source = np.concatenate([np.full(v.size, i) for i, v in enumerate(lams)])
    step = int(np.gcd.reduce(np.abs(H))) or 1
    all_bounds = error_bound(lam, x, y, B, normA, normB)
    keep = grid_representatives(lam, x, centroid, w, source=source, step=step, bounds=all_bounds)
    bounds = all_bounds[keep]
    reps, edges = fold(lam[keep], w), edge_weight(per_h[:, keep], H, system.time_invariant)
    # conjugate exponents of a real system (Im < 0 copies were not searched)
    conj = np.abs(reps.imag) > 1e-9 * np.maximum(np.abs(reps), w)
    conj &= np.abs(np.abs(reps.imag) - w / 2) > 1e-9 * w
    reps = np.concatenate([reps, fold(reps[conj].conj(), w)])
    bounds = np.concatenate([bounds, bounds[conj]])
    edges = np.concatenate([edges, edges[conj]])
    band = _coverage(disks, lo, hi)
    info = {
        "shifts": [complex(s) for s, _ in disks],
        "radii": [r for _, r in disks],
        "factorizations": len(disks),
        "size": A.shape[0],
        "frequencies": (lo, hi),
        "seconds": time.perf_counter() - t0,
    }
    if omega <= hi:
        log.warning("floquet(sparse): stopped at %d shifts below %.6g rad/s", max_shifts, hi)
        info["incomplete"] = True
    return floquet_result(reps, bounds, edges, w, "sparse", band=band, info=info)


def _coverage(disks: list[tuple[complex, float]], lo: float, hi: float) -> float:
    """Smallest half-width ``|Re|`` covered by the union of the disks along ``[lo, hi]``."""
    grid = np.linspace(lo, hi, 2001)
    half = np.zeros_like(grid)
    for s, r in disks:
        d2 = r * r - (grid - s.imag) ** 2
        h = np.sqrt(np.maximum(d2, 0.0)) - abs(s.real)
        half = np.maximum(half, np.where(d2 > 0, h, 0.0))
    return float(max(half.min(), 0.0))
