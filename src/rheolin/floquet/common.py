"""Pieces shared by the dense and sparse Hill paths: harmonic energies, folding, error bounds,
representatives.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .result import EPS, SAFETY

__all__ = []


# ----------------------------------------------------------------------------- shared pieces
def harmonic_energy(vecs: np.ndarray, n_h: int, n: int) -> np.ndarray:
    """Energy fraction per harmonic, shape ``(|H|, n_vec)``."""
    with np.errstate(under="ignore"):
        energy = np.abs(vecs) ** 2
    per_h = energy.reshape(n_h, 2 * n, -1).sum(axis=1)
    total = per_h.sum(axis=0, keepdims=True)
    return per_h / np.where(total > 0, total, 1.0)


def edge_weight(per_h: np.ndarray, H: np.ndarray, exact: bool = False) -> np.ndarray:
    """Energy fraction in the two outermost harmonics (0 when the truncation is exact)."""
    if exact:
        return np.zeros(per_h.shape[1])
    if H.size < 3:
        return per_h.sum(axis=0) if H.size else np.zeros(per_h.shape[1])
    return np.asarray(per_h[0] + per_h[-1])


def fold(lam: np.ndarray, w: float) -> np.ndarray:
    shift = np.ceil(lam.imag / w - 0.5)
    return np.asarray(lam - 1j * w * shift)


def error_bound(
    lam: np.ndarray, x: np.ndarray, y: np.ndarray, B: Any, normA: float, normB: float
) -> np.ndarray:
    """First-order bound ``eps (||A|| + |lam| ||B||) ||x|| ||y|| / |y^H B x|`` per column."""
    with np.errstate(under="ignore"):
        Bx = B @ x
        denom = np.abs(np.einsum("ij,ij->j", y.conj(), Bx))
        nx = np.linalg.norm(x, axis=0)
        ny = np.linalg.norm(y, axis=0)
    tiny = np.finfo(float).tiny
    return np.asarray(EPS * (normA + np.abs(lam) * normB) * nx * ny / np.maximum(denom, tiny))


def grid_representatives(
    lam: np.ndarray,
    x: np.ndarray,
    centroid: np.ndarray,
    w: float,
    limit: int | None = None,
    source: np.ndarray | None = None,
    step: int = 1,
    bounds: np.ndarray | None = None,
) -> np.ndarray:
    """Indices of distinct exponents, best centred first.

    Two eigenvalues whose difference is ``i j w1`` with ``j != 0`` a multiple of ``step`` (the
    gcd of the harmonic set) are copies of one exponent
    (the better centred one is kept); equal eigenvalues with non-parallel eigenvectors are a
    multiple exponent (both kept); the same eigenpair found twice (from two ``source``
    shifts, parallel eigenvectors) counts once.
    """
    order = np.argsort(np.abs(centroid), kind="stable")
    kept: list[int] = []
    for i in order:
        if limit is not None and len(kept) >= limit:
            break
        dup = False
        for j in kept:
            diff = lam[i] - lam[j]
            shift = round(diff.imag / w)
            close = 1e-9 * max(abs(lam[i]), w) + 1e-6 * w
            if bounds is not None:  # ill-conditioned exponents (Jordan blocks) scatter more
                close += SAFETY * (bounds[i] + bounds[j])
            if shift % step or abs(diff - 1j * shift * w) > close:
                continue
            if shift != 0:
                dup = True  # another copy of an exponent already kept
                break
            if source is None or source[i] == source[j]:
                continue
            xi, xj = x[:, i], x[:, j]
            with np.errstate(under="ignore"):
                cos = abs(np.vdot(xi, xj)) / (np.linalg.norm(xi) * np.linalg.norm(xj))
            if cos > 0.99:
                dup = True
                break
        if not dup:
            kept.append(int(i))
    return np.array(kept, dtype=int)
