"""From the representatives a lattice search selected to its result
(:class:`~rheolin.floquet.LatticeExponents`): each one polished, with its left vector, error
bound, truncation estimate (now, or deferred to :class:`Settler`), Gershgorin verdict where
the truncation does not resolve it, and the modes it resonates with (docs/stability.md).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..harmonics.lattice import Lattice
from ..system.periodic import PeriodicSystem
from .averaged import Averaged
from .checks import Outer, split_gaps
from .outcome import LatticeExponents
from .result import EPS, SAFETY, TRUNCATION_SAFETY
from .select import Candidate
from .shift_invert import BalancedPencil, harmonic_block, polish

__all__ = ["UNRESOLVED_EDGE"]


#: A representative with more energy than this on the outer shell is not resolved by the
#: truncation: its verdict comes from the Gershgorin discs of its modes.
UNRESOLVED_EDGE = 0.1


#: What a representative's Ritz vector is replaced by once its polished vector is made.
_SPENT = np.zeros(0, dtype=complex)


def lattice_result(
    pencil: BalancedPencil,
    system: PeriodicSystem,
    lattice: Lattice,
    avg: Averaged,
    reps: list[tuple[Candidate, bool]],
    clusters: list[np.ndarray],
    family_of: np.ndarray,
    discs: np.ndarray,
    *,
    expected: int,
    liouville: tuple[float, float],
    info: dict[str, Any],
    defer_truncation: bool = False,
) -> LatticeExponents:
    """The :class:`~rheolin.floquet.LatticeExponents` of the representatives ``reps``
    (``(candidate, conjugate_is_another_exponent)`` pairs of
    :func:`~rheolin.floquet.select.select`) of a search on ``lattice``: ``clusters`` of the
    averaged modes ``avg``, ``family_of`` each mode's cluster and ``discs`` their Gershgorin
    radii (zero where not computed). ``defer_truncation``: the truncation estimates are left
    to the result's ``settle(rows)`` (NaN until then)."""
    hill, w = pencil.hill, system.omega
    H, n = lattice.indices, system.n
    nh = H.size
    lam0 = avg.lam
    lams: list[complex] = []
    bounds, trunc, edges, cents, doms, partners = [], [], [], [], [], []
    vectors: list[np.ndarray | None] = []
    certified: list[bool] = []
    centres: list[complex] = []
    rates: list[complex] = []
    spread: list[float] = []
    related: list[list[complex]] = []
    radii: list[float] = []
    conj_index = _conjugate_index(lam0)
    outer = Outer(hill, avg) if nh > 0 else None
    deferred: list[tuple[complex, np.ndarray, np.ndarray]] = []  # (lam, q, u)
    radius: dict[int, float] = {}
    for c, conj_too in reps:
        # a representative the truncation does not resolve (its energy on the outer shells,
        # or taken only to fill its cluster) is judged by the Gershgorin discs of its modes
        unresolved = c.forced or c.edge > UNRESOLVED_EDGE
        ok = False
        if unresolved:
            modes = np.flatnonzero(family_of == c.search) if c.search >= 0 else np.zeros(0, int)
            need_r = [int(m) for m in modes if int(m) not in radius]
            if need_r:
                radius.update(zip(need_r, avg.gershgorin(system, need_r), strict=True))
            ok = bool(modes.size) and all(lam0[m].real + radius[int(m)] < 0 for m in modes)
        disc = max((radius[int(m)] for m in modes), default=0.0) if unresolved and ok else 0.0
        if c.polished is not None:  # tracked: polished already, its residual known
            lam_c, xq, u, yq, res = c.polished
        else:
            xq, _ = pencil.unbalanced(c.y)
            lam_c, xq, u, yq = polish(hill, c.lam, xq, w)
            # the pair's own residual enters its bound (a Ritz pair accepted wrongly then
            # gets a wide tolerance, never a confident verdict)
            res = pencil.residual(xq, lam_c)
        c.lam = lam_c
        # first-order vectors: right (q, s q), left (P^H u, u); balanced: R^-1 x, L^-1 y
        xb = pencil.first_order(xq, lam_c)
        yb = np.concatenate([yq / pencil.sq, u * pencil.sv])
        denom = abs(np.vdot(yb, pencil.B(xb)))
        nx, ny = np.linalg.norm(xb), np.linalg.norm(yb)
        # first order in the backward error: rounding's, or a tracked pair's residual
        err = max(EPS * (pencil.normA + abs(lam_c) * pencil.normB) * nx, res)
        bound = err * ny / max(denom, np.finfo(float).tiny)
        if outer is None:
            tau = 0.0
        elif defer_truncation:
            tau = float("nan")
            deferred.append((lam_c, xq, u))
        else:
            tau = outer.estimate(lam_c, xq, u)
        part = _partner(c, H, n, avg.WB, conj_index)
        c.y = _SPENT  # the result keeps the polished vector ``xb``; this one is not used again
        for lam_i in [c.lam, np.conj(c.lam)] if conj_too else [c.lam]:
            lams.append(complex(lam_i))
            vectors.append(xb if lam_i == c.lam else None)
            bounds.append(bound)
            trunc.append(tau)
            edges.append(c.edge)
            cents.append(c.centroid)
            doms.append(c.dominant if lam_i == c.lam else conj_index[c.dominant])
            partners.append(
                part
                if lam_i == c.lam
                else (-part[0], int(conj_index[part[1]]), int(conj_index[part[2]]))
            )
            certified.append(ok if unresolved else False)
            spread.append(disc if np.isnan(tau) else max(TRUNCATION_SAFETY * tau, disc))
            members = clusters[c.home] if c.home >= 0 else np.zeros(0, int)
            mid = complex(np.mean(lam0[members])) if members.size else complex("nan")
            centres.append(mid if lam_i == c.lam else complex(np.conj(mid)))
            rates.append(c.rate if lam_i == c.lam else complex(np.conj(c.rate)))
            related.append(
                [complex(np.mean(lam0[clusters[f]])) for f in c.families if f < len(clusters)]
            )
            radii.append(float(discs[members].max()) if members.size else np.inf)
    result = LatticeExponents(
        exponents=np.array(lams, dtype=complex),
        bounds=np.array(bounds, dtype=float),
        truncation=np.array(trunc, dtype=float),
        edge=np.array(edges, dtype=float),
        centroid=np.array(cents, dtype=float),
        dominant=np.array(doms, dtype=int),
        partner=partners,
        expected=expected,
        averaged=lam0,
        averaged_tol=np.maximum(SAFETY * avg.bound, 1e-10 * np.maximum(np.abs(lam0), w)),
        split_gap=split_gaps(np.array(lams, dtype=complex), H, w),
        certified=np.array(certified, dtype=bool),
        centre=np.array(centres, dtype=complex),
        order=np.full(len(lams), lattice.order, dtype=int),
        related=related,
        radius=np.array(radii, dtype=float),
        uncertainty=np.array(spread, dtype=float),
        unresolved=np.array(
            [c.forced or c.edge > UNRESOLVED_EDGE for c, cj in reps for _ in range(2 if cj else 1)],
            dtype=bool,
        ),
        liouville=liouville,
        info=info,
        vectors=vectors,
        indices=H,
        lattice=lattice,
        modes=avg,
        rate=np.array(rates, dtype=complex),
    )
    if deferred and outer is not None:
        result.settle = Settler(outer, deferred)
    return result


class Settler:
    """``settler(out, rows)``: the truncation estimates of those rows of ``out``, found by
    their exponent (a representative's row and its conjugate's share one estimate, computed
    once), so that the rows may have moved since (a confirmation keeps some coarse rows and
    appends finer ones).

    The result is an argument, not kept: a result holding a settler that holds the result
    is a reference cycle, which keeps the finer lattices' operators and PARDISO factors alive
    until a full garbage collection (bench/stability.py, design notes).
    """

    def __init__(
        self, outer: Outer, deferred: list[tuple[complex, np.ndarray, np.ndarray]]
    ) -> None:
        self.outer = outer
        self.requests = {complex(lam): (lam, q, u) for lam, q, u in deferred}
        self.known: dict[complex, float] = {}

    def __call__(self, out: LatticeExponents, rows: np.ndarray) -> None:
        for row in np.asarray(rows, dtype=int):
            if not np.isnan(out.truncation[row]):
                continue
            z = complex(out.exponents[row])
            key = z if z in self.requests else complex(np.conj(z))
            if key not in self.requests:
                continue  # not this lattice's exponent
            if key not in self.known:
                self.known[key] = self.outer.estimate(*self.requests[key])
            tau = self.known[key]
            out.truncation[row] = tau
            out.uncertainty[row] = max(out.uncertainty[row], TRUNCATION_SAFETY * tau)


def _partner(
    c: Candidate, H: np.ndarray, n: int, WB: np.ndarray, conj: np.ndarray
) -> tuple[int, int, int]:
    """What a representative resonates with: ``(shift, mode_a, mode_b)``, the time-averaged
    mode ``mode_a`` dominating the eigenvector at one harmonic and ``mode_b`` at another
    ``shift`` harmonics away (``(0, -1, -1)`` without one).

    Among the harmonics holding at least 1 % of the largest energy, a parametric resonance
    pairs a mode with its own conjugate (``2 w_j ~ shift w1``): the most energetic such pair
    is taken. Otherwise (a combination of two modes) the two most energetic harmonics are.
    The harmonics in between (the non-resonant steps of a secondary resonance, or a
    representative whose energy sits off harmonic 0) are passed over.
    """
    nh = H.size
    order = [int(i) for i in np.argsort(-c.energy, kind="stable")]
    top = c.energy[order[0]]
    big = [i for i in order if c.energy[i] >= 1e-2 * top]
    if len(big) < 2:
        return 0, -1, -1
    modes = {i: int(np.argmax(np.abs(WB @ harmonic_block(c.y, i, n, nh)))) for i in big}
    best: tuple[float, int, int] | None = None
    for a in big:
        for b in big:
            if b != a and conj[modes[a]] == modes[b] and H[b] != H[a]:
                score = float(c.energy[a] + c.energy[b])
                if best is None or score > best[0]:
                    best = (score, a, b)
    a, b = (best[1], best[2]) if best is not None else (big[0], big[1])
    return int(H[b] - H[a]), modes[a], modes[b]


def _conjugate_index(lam: np.ndarray) -> np.ndarray:
    """For each eigenvalue, the index of its conjugate (itself when real); ``-1`` maps to -1."""
    idx = np.array([int(np.argmin(np.abs(lam - np.conj(x)))) for x in lam], dtype=int)
    return np.append(idx, -1)
