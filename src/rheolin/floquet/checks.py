"""Checks of a lattice result: truncation estimate, Gershgorin discs, split gaps, Liouville's
identity.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..harmonics.hill import _dense, scaled_entries
from ..harmonics.hill_lattice import LatticeHill
from ..system.periodic import PeriodicSystem
from .averaged import MAX_AVERAGED_DENSE, _Averaged
from .outcome import LatticeExponents
from .result import TRUNCATION_SAFETY

__all__ = ["liouville_sum"]


class _Outer:
    """Second-order truncation correction from the harmonics just outside the lattice."""

    def __init__(self, hill: LatticeHill, avg: _Averaged) -> None:
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
        if self.avg.modal:
            ac, rr = a[:, self.cols], r[:, self.rows]
            # outer harmonics that both couplings reach (a third of them are exact zeros on
            # the gearbox: they add nothing)
            both = np.flatnonzero(np.any(ac != 0, axis=1) & np.any(rr != 0, axis=1))
            Ga = ac[both] @ self.Xq
            Gr = rr[both] @ self.Wv
            with np.errstate(divide="ignore", invalid="ignore"):
                term = -np.sum(Ga * Gr / (self.avg.lam[None, :] - s_o[both, None]))
        else:
            term = self._direct(a, r, s_o)
        val = abs(term / den)
        return float(val) if np.isfinite(val) else float("inf")

    def _direct(self, a: np.ndarray, r: np.ndarray, s_o: np.ndarray) -> complex:
        """Without a complete modal basis (massless DOFs): one LU of ``Q0(s)`` per harmonic."""
        block = self.hill.blocks[0]
        rows, cols, (K, D, M) = block.entries()
        n = self.hill.n
        total = 0j
        weight = np.linalg.norm(a, axis=1) * np.linalg.norm(r, axis=1)
        keep = np.flatnonzero(weight > 1e-14 * max(weight.max(), np.finfo(float).tiny))
        for i in keep:
            s = s_o[i]
            Q0 = sp.csc_array((K + s * D + s * s * M, (rows, cols)), shape=(n, n))
            try:
                z = spla.spsolve(Q0, r[i])
            except RuntimeError:
                return complex("inf")
            total += a[i] @ z
        return total


def _gershgorin(system: PeriodicSystem, avg: _Averaged, modes: list[int]) -> list[float]:
    """Gershgorin radii of time-averaged modes in the modal Hill matrix of the infinite
    lattice: ``sum_k sum_m |w_j^H E_k x_m|`` over every coefficient harmonic ``k`` (rows of
    the balanced first-order coupling in modal coordinates, ``M_k`` at the row's local
    frequency ``lambda_j - i k w1``). Every Hill exponent lies in the union of the discs of
    radius ``R_j`` about the copies ``lambda_j - i h w1``, for any truncation."""
    # kept on ``avg``: the balanced couplings, and each mode's radius (it does not depend on
    # the lattice; a finer lattice's confirmation asks again for the modes it settles)
    cache = getattr(avg, "_gershgorin", None)
    if cache is None or cache[0] is not system:
        radii: dict[int, float] = {}
        cache = (system, _coupling_terms(system, avg), radii)
        avg._gershgorin = cache  # type: ignore[attr-defined]
    _, terms, known = cache
    missing = sorted({int(m) for m in modes if int(m) not in known})
    if missing:
        known.update(zip(missing, _radii(system, avg, terms, missing), strict=True))
    return [known[int(m)] for m in modes]


def _coupling_terms(system: PeriodicSystem, avg: _Averaged) -> list[tuple[Any, ...]]:
    """Per coefficient harmonic ``k``: ``(k, *_compact(...))`` of the balanced couplings."""
    iq, iv = 1.0 / avg.sq, 1.0 / avg.sv
    terms = []
    for k in system.coefficient_harmonics:
        mats = [
            None if x is None else scaled_entries(x, iv, right)
            for x, right in ((system.K.get(k), iq), (system.D.get(k), iv), (system.M.get(k), iv))
        ]
        terms.append((k, *_compact(mats)))
    return terms


def _radii(
    system: PeriodicSystem, avg: _Averaged, terms: list[tuple[Any, ...]], modes: list[int]
) -> list[float]:
    """The radii of :func:`_gershgorin`, computed."""
    n, w = system.n, system.omega
    Wr = avg.W[:, modes].conj().T  # rows of the modal transform
    out = np.zeros(len(modes))
    low = Wr[:, n:]  # the couplings act on the v rows
    for k, rows, cq, cv, Kc, Dc, Mc in terms:
        if rows.size == 0:
            continue
        lr = low[:, rows]
        # the couplings touch a few DOFs (a gear mesh's): only those rows of the modal
        # transform enter, the rest of ``w_j^H E_k`` is zero (4x faster on the gearbox)
        total = np.zeros((len(modes), avg.X.shape[1]), dtype=complex)
        if Kc is not None:
            total += (lr @ Kc) @ avg.X[cq]
        if Dc is not None or Mc is not None:
            pv = lr @ Dc if Dc is not None else 0.0
            if Mc is not None:
                s = avg.lam[modes] - 1j * k * w
                pv = pv + s[:, None] * (lr @ Mc)
            total += pv @ avg.X[n + cv]
        out += np.abs(total).sum(axis=1)
    return out.tolist()


def _compact(mats: list[Any]) -> tuple[Any, ...]:
    """``(rows, q columns, v columns, K, D, M)``: the coupling matrices (entries from
    :func:`~rheolin.harmonics.hill.scaled_entries`, None where absent) as dense blocks on
    their nonzero rows and columns (K on the q columns, D and M on the v columns)."""
    none = np.zeros(0, dtype=np.int64)
    K, D, M = mats
    rows = np.unique(np.concatenate([a[0] for a in mats if a is not None] + [none]))
    cq = np.unique(K[1]) if K is not None else none
    cv = np.unique(np.concatenate([a[1] for a in (D, M) if a is not None] + [none]))

    def block(a: Any, cols: np.ndarray) -> np.ndarray | None:
        if a is None:
            return None
        out = np.zeros((rows.size, cols.size), dtype=complex)
        np.add.at(out, (np.searchsorted(rows, a[0]), np.searchsorted(cols, a[1])), a[2])
        return out

    return rows, cq, cv, block(K, cq), block(D, cv), block(M, cv)


def _split_gaps(lam: np.ndarray, H: np.ndarray, w: float) -> np.ndarray:
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

    dense = _dense
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


def _agree(coarse: np.ndarray, fine: np.ndarray, fine_unresolved: np.ndarray) -> bool:
    """Two truncations agree on a cluster: as many exponents, each within a tenth of its
    distance from the axis of one of the other order, all of them stable."""
    if coarse.size == 0 or coarse.size != fine.size:
        return False
    moved = max(float(np.min(np.abs(fine - z0))) for z0 in coarse)
    worst = float(max(coarse.real.max(), fine.real.max()))
    del fine_unresolved  # agreement is the test, resolved or not
    return worst < 0 and TRUNCATION_SAFETY * moved < -worst


def _certify(out: LatticeExponents, mine: np.ndarray, coarse: np.ndarray, fine: np.ndarray) -> None:
    moved = max(float(np.min(np.abs(fine - z0))) for z0 in coarse)
    hit = mine & out.unresolved
    out.certified[hit] = True
    out.uncertainty[hit] = np.maximum(out.uncertainty[hit], TRUNCATION_SAFETY * moved)
