"""Checks of a lattice result: truncation estimate, split gaps, Liouville's identity, and
agreement between two truncations (the Gershgorin discs are the averaged modes':
:meth:`~rheolin.floquet.averaged.Averaged.gershgorin`).
"""

from __future__ import annotations

import numpy as np

from ..harmonics.hill import dense
from ..harmonics.hill_lattice import LatticeHill
from ..system.periodic import PeriodicSystem
from .averaged import MAX_AVERAGED_DENSE, Averaged
from .outcome import LatticeExponents
from .result import TRUNCATION_SAFETY
from .shift_invert import PatternLU

__all__ = ["liouville_sum"]


class Outer:
    """Second-order truncation correction from the harmonics just outside the lattice."""

    def __init__(self, hill: LatticeHill, avg: Averaged) -> None:
        self.hill = hill
        self.avg = avg
        self.O, self.oi, self.io = hill.outer()
        n = hill.n
        # the DOFs the time variation touches: rows of the couplings to the outside (where
        # Q_OI q is nonzero) and their columns (where Q_IO^H u is); often a few (the gear
        # mesh DOFs), which makes the modal sums that much cheaper
        self.rows = np.unique(self.oi.rows % n) if self.oi.nnz else np.zeros(0, int)
        self.cols = np.unique(self.io.cols % n) if self.io.nnz else np.zeros(0, int)
        self.Xq = (avg.X[:n] / avg.sq[:, None])[self.cols]  # Tq X_top
        self.Wv = (avg.W[n:].conj() / avg.sv[:, None])[self.rows]  # Tv-weighted conj(W_bot)
        self.factor = PatternLU()  # Q0(s) at every outer harmonic: one pattern

    def estimate(self, lam: complex, q: np.ndarray, u: np.ndarray) -> float:
        hill, n, w = self.hill, self.hill.n, self.hill.w
        if self.O.size == 0:
            return 0.0
        r = np.asarray(self.oi.Q(lam, w) @ q).reshape(self.O.size, n)
        a = np.asarray(self.io.Q(lam, w).T @ np.conj(u)).reshape(self.O.size, n)  # conj(Q^H u)
        den = np.vdot(u, hill.inner.dQ(lam, w) @ q)
        if den == 0:
            return float("inf")
        s_o = lam + 1j * w * self.O.astype(float)
        if getattr(self.avg, "partial", False):
            # a band leaves modes out: the sum over the outer harmonics exactly, one sparse
            # LU of Q0(s) each (docs/stability.md, 8.3)
            term = self._direct(a, r, s_o)
        elif self.avg.modal:
            ac, rr = a[:, self.cols], r[:, self.rows]
            # only the outer harmonics that both couplings reach: the others are exact
            # zeros, which add nothing (bench/stability.py, design notes)
            both = np.flatnonzero(np.any(ac != 0, axis=1) & np.any(rr != 0, axis=1))
            Ga = ac[both] @ self.Xq
            Gr = rr[both] @ self.Wv
            with np.errstate(divide="ignore", invalid="ignore"):
                term = -np.sum(Ga * Gr / (self.avg.lam[None, :] - s_o[both, None]))
        else:
            term = self._direct(a, r, s_o)
        val = abs(term) / abs(den)
        return float(val) if np.isfinite(val) else float("inf")

    def _direct(self, a: np.ndarray, r: np.ndarray, s_o: np.ndarray) -> complex:
        """Without a complete modal basis (massless DOFs, or a band of modes): one LU of
        ``Q0(s)`` per outer harmonic."""
        block = self.hill.blocks[0]
        rows, cols, (K, D, M) = block.entries()  # in CSC order, no duplicates
        n = self.hill.n
        indptr = np.searchsorted(cols, np.arange(n + 1))
        total = 0j
        weight = np.linalg.norm(a, axis=1) * np.linalg.norm(r, axis=1)
        keep = np.flatnonzero(weight > 1e-14 * max(weight.max(), np.finfo(float).tiny))
        for i in keep:
            s = s_o[i]
            try:
                lu = self.factor.pattern(K + s * D + s * s * M, rows, indptr)
                z = lu.solve(np.asarray(r[i], dtype=complex))
            except RuntimeError:
                return complex("inf")
            total += a[i] @ z
        return total


def split_gaps(lam: np.ndarray, H: np.ndarray, w: float) -> np.ndarray:
    """Distance of each exponent to the nearest copy of its conjugate at a lattice shift
    (``|2 Im lambda - h w1|``, ``h`` in the lattice): where a complex pair can collide with it
    and split into two exponents of different real parts. Zero for locked (self-conjugate)
    exponents, whose partner is the other locked one: there the gap is their real distance."""
    out = np.empty(lam.size)
    hw = np.sort(H.astype(float) * w)
    for i, z in enumerate(lam):
        target = 2.0 * z.imag
        j = np.clip(np.searchsorted(hw, target), 1, hw.size - 1) if hw.size > 1 else 0
        near = hw[max(j - 1, 0) : j + 1]
        gap = float(np.min(np.abs(near - target))) if near.size else np.inf
        if gap <= 1e-9 * max(abs(z), w):  # locked: the partner is another locked exponent
            locked = [
                abs(z.real - x.real)
                for k, x in enumerate(lam)
                if (k != i and abs(2.0 * x.imag - target) <= 1e-6 * max(abs(z), w))
                or (k != i and np.min(np.abs(hw - (x.imag + z.imag))) <= 1e-6 * max(abs(z), w))
            ]
            gap = min(locked) if locked else np.inf
        out[i] = gap
    return out


def liouville_sum(system: PeriodicSystem) -> tuple[float, float]:
    """``sum Re lambda`` over all ``2 n`` Floquet exponents by Liouville's formula,
    ``-mean_t tr(M(t)^-1 D(t))``, and an uncertainty; ``(nan, inf)`` when ``M_0`` is singular
    or too large to invert densely.

    With a time-varying ``M`` the mean is expanded to second order in ``M_k``; the size of
    the second-order terms is returned as the uncertainty (the neglected terms are smaller).
    """
    n = system.n
    M0 = system.M.get(0)
    if M0 is None or n > MAX_AVERAGED_DENSE // 2:
        return float("nan"), float("inf")

    try:
        Minv = np.linalg.inv(dense(M0))
    except np.linalg.LinAlgError:
        return float("nan"), float("inf")
    if not np.all(np.isfinite(Minv)) or np.linalg.cond(dense(M0)) > 1e12:
        return float("nan"), float("inf")
    D0 = dense(system.D[0]) if 0 in system.D else np.zeros((n, n))
    G = Minv @ D0
    value = float(np.trace(G).real)
    second = 0.0
    for k, Mk in system.M.items():
        if k == 0:
            continue
        # tr(P Y) with P = M0^-1 M_k nonzero on the columns c of M_k only: the sum over
        # P[:, c] * Y[c, :]^T (M_k touches a few DOFs: no n x n products per harmonic)
        Mk = dense(Mk)
        r = np.flatnonzero(np.any(Mk != 0, axis=1))
        c = np.flatnonzero(np.any(Mk != 0, axis=0))
        if not c.size:
            continue
        P = Minv[:, r] @ Mk[np.ix_(r, c)]
        term = 0.0
        if -k in system.D:  # tr(M0^-1 M_k M0^-1 D_-k)
            term = term - np.sum(P * (Minv[c] @ dense(system.D[-k])).T)
        if -k in system.M:  # tr(M0^-1 M_k M0^-1 M_-k M0^-1 D_0)
            term = term + np.sum(P * ((Minv[c] @ dense(system.M[-k])) @ G).T)
        second += float(np.real(term))
    return -(value + second), abs(second) + 1e-12 * abs(value)


def agree(coarse: np.ndarray, fine: np.ndarray, fine_unresolved: np.ndarray) -> bool:
    """Two truncations agree on a cluster: as many exponents, each within a tenth of its
    distance from the axis of one of the other order, all of them stable."""
    if coarse.size == 0 or coarse.size != fine.size:
        return False
    moved = max(float(np.min(np.abs(fine - z0))) for z0 in coarse)
    worst = float(max(coarse.real.max(), fine.real.max()))
    del fine_unresolved  # agreement is the test, resolved or not
    return worst < 0 and TRUNCATION_SAFETY * moved < -worst


def certify(out: LatticeExponents, mine: np.ndarray, coarse: np.ndarray, fine: np.ndarray) -> None:
    moved = max(float(np.min(np.abs(fine - z0))) for z0 in coarse)
    hit = mine & out.unresolved
    out.certified[hit] = True
    out.uncertainty[hit] = np.maximum(out.uncertainty[hit], TRUNCATION_SAFETY * moved)
