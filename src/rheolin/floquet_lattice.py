"""Floquet exponents on a harmonic lattice (docs/stability.md).

For a system whose time variation comes from a few sources (gear meshes, 1x/2x of shafts)
the dense Hill truncation ``-N..N`` in units of ``w1`` is hopeless: a hunting-tooth gearbox
has ``w1`` = input speed / 4757 and would need millions of harmonics. Here the Hill problem is
truncated to a lattice (:mod:`rheolin.lattice`) and solved near each mode of the
time-averaged system:

1. the exponents ``lambda_j`` of the time-averaged system (``Im >= 0``) are the *targets*;
2. at each target ``sigma``, shift-invert Arnoldi on the lattice Hill pencil, one sparse LU of
   the second-order operator ``Q(sigma)`` (:class:`~rheolin.hill_lattice.LatticeHill`), finds
   the exponents nearest it; targets inside half the radius reached count as searched;
3. of the copies ``lambda + i h w1`` of each exponent, the representative is the one whose
   eigenvector's energy sits at the centre of the lattice (smallest energy-weighted shell);
   copies (recognized by the shift between their most energetic harmonics), duplicates and the
   conjugate half are removed, and the count is checked against the ``2 n`` exponents;
4. each representative gets its left eigenvector (one LU at the exponent), a first-order
   rounding bound and a truncation estimate: the second-order (Feshbach) correction from the
   harmonics one coefficient step outside the lattice,
   ``delta = u^H Q_IO Q_OO^-1 Q_OI q / (u^H Q'(lambda) q)``, ``Q_OO`` block-diagonal and
   inverted through the averaged modes.

Spurious exponents at the lattice boundary (the known failure of multi-frequency Hill
methods) have their energy on the outer shells: a better centred copy of the same exponent
is always preferred, and a boundary eigenvector left as a representative carries a large
truncation estimate, which makes the verdict undecided instead of wrong.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla

from .hill import hill_pencil, state_scaling
from .hill_lattice import LatticeHill
from .lattice import Lattice
from .system import PeriodicSystem

__all__ = ["MAX_AVERAGED_DENSE", "LatticeExponents", "lattice_exponents", "lattice_memory"]

log = logging.getLogger(__name__)

_EPS = float(np.finfo(float).eps)
#: Dense eigen-decomposition of the time-averaged pencil up to this size (``2 n``).
MAX_AVERAGED_DENSE = 4000
#: A representative with more energy than this on the outer shell is not resolved by the
#: truncation: its verdict comes from the Gershgorin discs of its modes.
UNRESOLVED_EDGE = 0.1
#: Unresolved exponents are confirmed when a finer lattice moves their real part by less
#: than ``1 / TRUNCATION_SAFETY`` of it.
TRUNCATION_SAFETY = 10.0
#: Rounding bounds are widened by this factor (as in :mod:`rheolin.floquet`).
SAFETY = 100.0
#: Estimated LU fill of the lattice operator (entries of the factors / entries of ``Q``).
LU_FILL = 12.0
#: SuperLU options for the lattice operator: column AMD with threshold pivoting that prefers
#: the diagonal (half the fill of partial pivoting on the gearbox; the Newton step on each
#: representative uses Q itself, so the factor's accuracy does not limit the exponents).
SPLU: dict[str, Any] = {"permc_spec": "COLAMD", "diag_pivot_thresh": 0.1}
#: Arnoldi: checkpoints (basis sizes) and the relative residual of an accepted Ritz pair.
ARNOLDI_STEPS = (10, 16, 24, 36, 54)
ARNOLDI_TOL = 1e-10
#: A target's search stops at a centred Ritz vector holding this share of its mode (of the
#: strongest mode's weight at harmonic 0): strongly mixed modes have no single owner.
ACCEPT_WEIGHT = 0.25
#: Averaged exponents closer than this (relative) are searched together.
CLUSTER_TOL = 1e-4
#: A Ritz vector counts for its target's search when its energy centroid is at most this
#: (0.5: split evenly between harmonic 0 and a neighbour, as in a principal resonance).
CENTRED = 0.5 + 1e-3
#: Eigenvectors of one value are dependent when the smallest singular value of the stacked
#: unit vectors is below this fraction of the largest.
DEPENDENT = 1e-3


@dataclass
class _Candidate:
    lam: complex
    y: np.ndarray  # balanced first-order right eigenvector over the lattice
    energy: np.ndarray  # energy fraction per lattice harmonic
    centroid: float
    edge: float
    top: tuple[int, int]  # the two most energetic harmonics (indices, not positions)
    dominant: int  # averaged mode with the largest weight at harmonic 0
    shift: int
    weights: np.ndarray  # modal weights at harmonic 0, largest = 1
    slack: float = 0.0  # rounding error of the dominant averaged exponent (x SAFETY)
    families: tuple[int, ...] = ()  # clusters it can stand for, most likely first
    forced: bool = False  # taken only to fill its cluster (see _fill)
    search: int = -1  # the cluster whose search found it
    home: int = -1  # the cluster it stands for


@dataclass
class LatticeExponents:
    """Representatives of the Floquet exponents on a lattice, with their diagnostics.

    ``exponents`` holds one copy per exponent (the one centred on harmonic 0, not folded),
    the conjugates included; the other arrays are aligned with it.
    """

    exponents: np.ndarray
    bounds: np.ndarray
    truncation: np.ndarray
    edge: np.ndarray
    centroid: np.ndarray
    dominant: np.ndarray
    partner: list[tuple[int, int]]
    expected: int
    averaged: np.ndarray
    averaged_tol: np.ndarray
    split_gap: np.ndarray
    certified: np.ndarray
    centre: np.ndarray
    unresolved: np.ndarray
    order: np.ndarray
    uncertainty: np.ndarray
    liouville: tuple[float, float]
    info: dict[str, Any] = field(default_factory=dict)
    related: list[list[complex]] = field(default_factory=list)
    radius: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def complete(self) -> bool:
        """True when as many exponents were found as the averaged system has."""
        return bool(self.exponents.size >= self.expected)


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
        A, B = hill_pencil(system, [0])
        Ad, Bd = A.toarray(), B.toarray()
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
        self.sq, self.sv = state_scaling(system)
        self.n = n


def lattice_memory(system: PeriodicSystem, lattice: Lattice, k: int = 8) -> int:
    """Estimated peak memory [bytes] of :func:`lattice_exponents` on ``lattice``.

    Counted without building anything: the entries of the lattice operator (from the block
    patterns and the number of harmonic pairs each coefficient harmonic couples), its LU at
    :data:`LU_FILL` times those entries, the Arnoldi basis, and the dense averaged modes.
    """
    from .operator import _Block

    H = lattice.indices
    n = system.n
    nnz = 0
    for k_h in [0, *system.coefficient_harmonics]:
        pos = np.minimum(np.searchsorted(H, H + k_h), H.size - 1)
        pairs = int(np.count_nonzero(H[pos] == H + k_h))
        if not pairs:
            continue
        block = _Block(system.M.get(k_h), system.D.get(k_h), system.K.get(k_h), n, system.is_sparse)
        nnz += pairs * int(block.entries()[0].size)
    size2 = 2 * n * H.size
    ncv = max(2 * k + 1, 20)
    return int(
        nnz * 16 * (6 + LU_FILL) + size2 * 16 * (ncv + 8) + (2 * n) ** 2 * 16 * 6 + 64 * 2**20
    )


def lattice_exponents(
    system: PeriodicSystem,
    lattice: Lattice,
    *,
    near: np.ndarray | None = None,
) -> LatticeExponents:
    """Representatives of the Floquet exponents of ``system`` on ``lattice``.

    See the module docstring for the method. ``near`` restricts the search to the
    time-averaged modes nearest these values (for tracking one exponent across speeds); the
    result is then partial (``expected`` is the number of those modes).
    """
    t0 = time.perf_counter()
    n, w = system.n, system.omega
    H = lattice.indices
    nh = H.size
    if 0 not in set(H.tolist()):
        raise ValueError("the lattice must contain harmonic 0")
    avg = _Averaged(system)
    hill = LatticeHill(system, H)
    sq_rep, sv_rep = np.tile(avg.sq, nh), np.tile(avg.sv, nh)
    Mconv = hill.inner.Mconv()
    centre = lattice.position(0)
    shell = lattice.shell.astype(float)
    boundary = lattice.boundary
    lam0 = avg.lam
    scale0 = np.maximum(np.abs(lam0), w)
    upper = np.flatnonzero(lam0.imag >= -1e-9 * scale0)
    if near is not None:
        picks = {int(np.argmin(np.abs(lam0 - z))) for z in np.atleast_1d(near)}
        picks = {
            j
            if lam0[j].imag >= -1e-9 * scale0[j]
            else int(np.argmin(np.abs(lam0 - np.conj(lam0[j]))))
            for j in picks
        }
        upper = np.array(sorted(picks), dtype=int)
    targets = upper[np.argsort(lam0[upper].imag, kind="stable")]
    size = 2 * n * nh
    pool: list[_Candidate] = []
    shifts: list[complex] = []
    lu_seconds = 0.0
    arnoldi_seconds = 0.0
    rng = np.random.default_rng(12345)

    def to_unbalanced(yb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return yb[: n * nh] / sq_rep, yb[n * nh :] / sv_rep

    def candidate(yb: np.ndarray, lam: complex, shift: int) -> _Candidate:
        with np.errstate(under="ignore"):
            e2 = np.abs(yb) ** 2
        e = e2[: n * nh].reshape(nh, n).sum(axis=1) + e2[n * nh :].reshape(nh, n).sum(axis=1)
        tot = e.sum()
        e = e / tot if tot > 0 else e
        top = np.argsort(-e, kind="stable")[:2]

        def block(i: int) -> np.ndarray:
            return np.concatenate(
                [yb[i * n : (i + 1) * n], yb[n * nh + i * n : n * nh + (i + 1) * n]]
            )

        mw = np.abs(avg.WB @ block(centre))
        dom = int(np.argmax(mw))
        # rounding scatter: that of the averaged mode carrying the most energetic harmonic
        mt = np.abs(avg.WB @ block(int(top[0])))
        at_top = int(np.argmax(mt))
        # the clusters it may stand for: modes carrying its energy at 0 or at its top harmonic
        share = np.maximum(mw / max(mw.max(), 1e-300), mt / max(mt.max(), 1e-300))
        fam: list[int] = []
        for m in np.argsort(-share, kind="stable"):
            if share[m] < ACCEPT_WEIGHT:
                break
            f = int(family_of[m])
            if f >= 0 and f not in fam:
                fam.append(f)
        return _Candidate(
            complex(lam),
            yb,
            e,
            float(shell @ e),
            float(e[boundary].sum()),
            (int(H[top[0]]), int(H[top[-1]])),
            dom,
            shift,
            mw / mw[dom] if mw[dom] > 0 else mw,
            SAFETY * float(avg.bound[at_top]),
            tuple(fam),
        )

    def share(c: _Candidate, cid: int) -> float:
        """Energy fraction of the cluster's modes (and their conjugates) over all harmonics."""
        blocks = np.concatenate(
            [c.y[: n * nh].reshape(nh, n), c.y[n * nh :].reshape(nh, n)], axis=1
        )
        modal = np.abs(blocks @ avg.WB.T) ** 2
        mine = np.flatnonzero(family_of == cid)
        total = modal.sum()
        return float(modal[:, mine].sum() / total) if total > 0 else 0.0

    def search(cid: int) -> list[_Candidate]:
        """Exponents of one cluster of (nearly) equal averaged exponents, centred copies."""
        nonlocal lu_seconds, arnoldi_seconds
        cluster = clusters[cid]
        sigma = complex(np.mean(lam0[cluster]))
        need = quotas[cid]
        t1 = time.perf_counter()
        lu = _factor(hill, sigma, w)
        sigma = lu.sigma
        lu_seconds += time.perf_counter() - t1
        P = hill.inner.P(sigma, w)
        S = hill.s(sigma)

        def apply(yb: np.ndarray) -> np.ndarray:
            # balanced (A - sigma B)^-1 B y through one solve with Q(sigma)
            xq, xv = to_unbalanced(yb)
            q = -lu.solve(np.asarray(Mconv @ xv + P @ xq))
            return np.concatenate([q * sq_rep, (xq + S * q) * sv_rep])

        v0 = np.zeros(size, dtype=complex)
        mix = rng.standard_normal(cluster.size) + 1j * rng.standard_normal(cluster.size)
        v0[centre * n : (centre + 1) * n] = avg.X[:n, cluster] @ mix
        v0[n * nh + centre * n : n * nh + (centre + 1) * n] = avg.X[n:, cluster] @ mix
        # a little of everything: an exact eigenvector would end the Krylov space at once
        v0 += 1e-3 * (rng.standard_normal(size) + 1j * rng.standard_normal(size)) / np.sqrt(size)
        t2 = time.perf_counter()
        shifts.append(sigma)
        found_here: list[_Candidate] = []

        def accept(theta: np.ndarray, vecs: np.ndarray) -> bool:
            found_here.clear()
            lam = sigma + 1.0 / theta
            for i in range(theta.size):
                found_here.append(candidate(vecs[:, i], lam[i], len(shifts) - 1))
            mine = [c for c in found_here if c.centroid <= CENTRED and cid in c.families]
            satisfied[0] = _count(_select(mine, {cid: need}, w, nh)) >= need
            return satisfied[0]

        satisfied = [False]
        _arnoldi(apply, v0, accept, steps=ARNOLDI_STEPS, tol=ARNOLDI_TOL)
        arnoldi_seconds += time.perf_counter() - t2
        for c in found_here:
            c.search = cid
        if not satisfied[0]:
            short.append(sigma)
        return found_here

    short: list[complex] = []
    clusters = _clusters(lam0, targets, w)
    quotas = {
        i: sum(1 if abs(lam0[c].imag) <= 1e-9 * scale0[c] else 2 for c in cl)
        for i, cl in enumerate(clusters)
    }
    family_of = np.full(lam0.size, -1, dtype=int)
    for i, cl in enumerate(clusters):
        family_of[cl] = i
    for m in np.flatnonzero(family_of < 0):  # the conjugates stand for their targets
        family_of[m] = family_of[int(np.argmin(np.abs(lam0 - np.conj(lam0[m]))))]
    # clusters whose Gershgorin discs lie left of the axis need no search: none of their
    # exponents can be unstable (every exponent lies in the union of the discs)
    discs = np.zeros(lam0.size)
    skipped: list[int] = []
    if near is None and lam0.size:
        upper_modes = [int(m) for cl in clusters for m in cl]
        discs[upper_modes] = _gershgorin(system, avg, upper_modes)
        for cid, cl in enumerate(clusters):
            if np.all(lam0[cl].real + discs[cl] < -1e-6 * np.maximum(np.abs(lam0[cl]), w)):
                skipped.append(cid)
                quotas[cid] = 0
    for cid in range(len(clusters)):
        if cid not in skipped:
            pool.extend(search(cid))

    expected = int(sum(quotas.values()))
    reps = _select(pool, quotas, w, nh, share=share)
    # left eigenvectors, error bounds and truncation estimates of the representatives
    A_b, B_b = hill_pencil(system, H)
    normA, normB = spla.norm(A_b, 1), spla.norm(B_b, 1)
    del A_b
    lams, bounds, trunc, edges, cents, doms, partners = [], [], [], [], [], [], []
    certified: list[bool] = []
    centres: list[complex] = []
    spread: list[float] = []
    related: list[list[complex]] = []
    radii: list[float] = []
    conj_index = _conjugate_index(lam0)
    outer = _Outer(hill, avg) if nh > 0 else None
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
                radius.update(zip(need_r, _gershgorin(system, avg, need_r), strict=True))
            ok = bool(modes.size) and all(lam0[m].real + radius[int(m)] < 0 for m in modes)
        disc = max((radius[int(m)] for m in modes), default=0.0) if unresolved and ok else 0.0
        xq, _ = to_unbalanced(c.y)
        lam_c, xq, u, yq = _polish(hill, c.lam, xq, w)
        c.lam = lam_c
        # first-order vectors: right (q, s q), left (P^H u, u); balanced: R^-1 x, L^-1 y
        xb = np.concatenate([xq * sq_rep, hill.s(lam_c) * xq * sv_rep])
        yb = np.concatenate([yq / sq_rep, u * sv_rep])
        denom = abs(np.vdot(yb, B_b @ xb))
        nx, ny = np.linalg.norm(xb), np.linalg.norm(yb)
        bound = _EPS * (normA + abs(lam_c) * normB) * nx * ny / max(denom, np.finfo(float).tiny)
        tau = outer.estimate(lam_c, xq, u) if outer is not None else 0.0
        part = _partner(c, H, n, avg.WB)
        for lam_i in [c.lam, np.conj(c.lam)] if conj_too else [c.lam]:
            lams.append(complex(lam_i))
            bounds.append(bound)
            trunc.append(tau)
            edges.append(c.edge)
            cents.append(c.centroid)
            doms.append(c.dominant if lam_i == c.lam else conj_index[c.dominant])
            partners.append(part if lam_i == c.lam else (-part[0], conj_index[part[1]]))
            certified.append(ok if unresolved else False)
            spread.append(max(TRUNCATION_SAFETY * tau, disc))
            members = clusters[c.home] if c.home >= 0 else np.zeros(0, int)
            mid = complex(np.mean(lam0[members])) if members.size else complex("nan")
            centres.append(mid if lam_i == c.lam else complex(np.conj(mid)))
            related.append(
                [complex(np.mean(lam0[clusters[f]])) for f in c.families if f < len(clusters)]
            )
            radii.append(float(discs[members].max()) if members.size else np.inf)
    info = {
        "lattice_size": nh,
        "lattice_order": lattice.order,
        "hill_size": size,
        "shifts": len(shifts),
        "lu_seconds": lu_seconds,
        "arnoldi_seconds": arnoldi_seconds,
        "seconds": time.perf_counter() - t0,
        "short_searches": [complex(x) for x in short],
        "certified_modes": np.concatenate(
            [lam0[clusters[c]] for c in skipped] + [np.zeros(0, complex)]
        ),
        "certified_radii": np.concatenate([discs[clusters[c]] for c in skipped] + [np.zeros(0)]),
    }
    return LatticeExponents(
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
        split_gap=_split_gaps(np.array(lams, dtype=complex), H, w),
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
        liouville=liouville_sum(system),
        info=info,
    )


def _arnoldi(
    apply: Any, v0: np.ndarray, accept: Any, *, steps: tuple[int, ...], tol: float
) -> None:
    """Arnoldi on ``apply`` from ``v0`` (no restarts); at each checkpoint the converged Ritz
    pairs (residual ``<= tol |theta|``) are passed to ``accept(theta, vectors)``, which says
    whether to stop."""
    m_max = steps[-1]
    size = v0.size
    m_max = min(m_max, size)
    V = np.empty((m_max + 1, size), dtype=complex)
    Hm = np.zeros((m_max + 1, m_max), dtype=complex)
    V[0] = v0 / np.linalg.norm(v0)
    checkpoints = {min(s, m_max) for s in steps}
    for j in range(m_max):
        wv = apply(V[j])
        basis = V[: j + 1]
        h = np.conj(basis @ np.conj(wv))
        wv = wv - h @ basis
        h2 = np.conj(basis @ np.conj(wv))  # second Gram-Schmidt pass
        wv = wv - h2 @ basis
        Hm[: j + 1, j] = h + h2
        beta = float(np.linalg.norm(wv))
        Hm[j + 1, j] = beta
        m = j + 1
        ended = beta <= 1e-14 * float(np.abs(Hm[: j + 2, : j + 1]).max())
        if not ended:
            V[j + 1] = wv / beta
        if m in checkpoints or ended or m == m_max:
            theta, Svec = np.linalg.eig(Hm[:m, :m])
            res = beta * np.abs(Svec[-1, :]) if not ended else np.zeros(m)
            good = res <= tol * np.abs(theta)
            if good.any():
                vecs = V[:m].T @ Svec[:, good]
                if accept(theta[good], vecs) or ended:
                    return
            if ended:
                return


def confirm_unresolved(
    system: PeriodicSystem, out: LatticeExponents, finer: Lattice
) -> LatticeExponents:
    """Settle the unresolved, uncertified representatives on a finer lattice.

    Their clusters are searched again on ``finer`` (only near them). Where the finer lattice
    resolves a cluster, its exponents replace the coarse ones (each exponent keeps its own
    ``order``); where it does not either, the cluster is confirmed when its largest real
    part is negative at both orders and changes by less than ``1 / TRUNCATION_SAFETY`` of
    its size (the verdict does not move with the truncation). Records
    ``info["confirmed"]``.
    """
    todo = out.unresolved & ~out.certified
    if not todo.any():
        return out
    centres = np.unique(out.centre[todo & (out.centre.imag >= 0)])
    centres = centres[np.isfinite(centres)]
    if centres.size == 0:
        return out
    fine = lattice_exponents(system, finer, near=centres)
    fields = (
        "exponents", "bounds", "truncation", "edge", "centroid", "dominant", "certified",
        "centre", "unresolved", "order", "uncertainty", "radius",
    )  # fmt: skip
    keep = np.ones(out.exponents.size, dtype=bool)
    take = np.zeros(fine.exponents.size, dtype=bool)
    replaced = confirmed = 0

    def members(arr: np.ndarray, z: complex) -> np.ndarray:
        tol = CLUSTER_TOL * max(abs(z), system.omega)
        return (np.abs(arr - z) <= tol) | (np.abs(arr - np.conj(z)) <= tol)

    every = np.any([members(out.centre, z) for z in centres], axis=0)
    there_all = np.any([members(fine.centre, z) for z in centres], axis=0)
    if not fine.unresolved[there_all].any() and there_all.sum() == every.sum():
        # the finer lattice resolves every cluster: take all of them (their attribution to
        # one cluster or another may differ between orders; the set is what counts)
        keep &= ~every
        take |= there_all
        replaced = int(centres.size)
        centres = centres[:0]
    left: list[complex] = []
    for z in centres:
        mine, there = members(out.centre, z), members(fine.centre, z)
        if not there.any():
            left.append(z)
            continue
        if not fine.unresolved[there].any() and there.sum() == mine.sum():
            keep &= ~mine
            take |= there
            replaced += 1
        elif _agree(out.exponents[mine], fine.exponents[there], fine.unresolved[there]):
            _certify(out, mine, out.exponents[mine], fine.exponents[there])
            confirmed += 1
        else:
            left.append(z)
    if left:
        # mixed neighbours trade exponents between orders: judge what is left as one group,
        # by its largest real part, which must stay put and keep a margin of a tenth of the
        # group's coupling radius (so that agreement by chance, both truncations sitting at
        # the undisturbed damping of a strongly coupled mode, does not count)
        mine = np.any([members(out.centre, z) for z in left], axis=0)
        there = np.any([members(fine.centre, z) for z in left], axis=0)
        radius = max(float(np.max(out.radius[mine], initial=0.0)), 0.0)
        a = float(out.exponents.real[mine].max()) if mine.any() else 0.0
        b = float(fine.exponents.real[there].max()) if there.any() else 0.0
        if (
            there.any()
            and a < 0
            and b < 0
            and TRUNCATION_SAFETY * abs(a - b) < -max(a, b)
            and -max(a, b) > 0.1 * radius
        ):
            hit = mine & out.unresolved
            out.certified[hit] = True
            out.uncertainty[hit] = np.maximum(out.uncertainty[hit], TRUNCATION_SAFETY * abs(a - b))
            confirmed += len(left)
    for name in fields:
        setattr(out, name, np.concatenate([getattr(out, name)[keep], getattr(fine, name)[take]]))
    out.partner = [p for p, k in zip(out.partner, keep, strict=True) if k] + [
        p for p, t in zip(fine.partner, take, strict=True) if t
    ]
    out.related = [r for r, k in zip(out.related, keep, strict=True) if k] + [
        r for r, t in zip(fine.related, take, strict=True) if t
    ]
    out.split_gap = _split_gaps(out.exponents, finer.indices, system.omega)
    out.info["confirmed"] = {
        "order": finer.order,
        "clusters": int(centres.size),
        "replaced": replaced,
        "confirmed": confirmed,
    }
    return out


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


def _gershgorin(system: PeriodicSystem, avg: _Averaged, modes: list[int]) -> list[float]:
    """Gershgorin radii of time-averaged modes in the modal Hill matrix of the infinite
    lattice: ``sum_k sum_m |w_j^H E_k x_m|`` over every coefficient harmonic ``k`` (rows of
    the balanced first-order coupling in modal coordinates, ``M_k`` at the row's local
    frequency ``lambda_j - i k w1``). Every Hill exponent lies in the union of the discs of
    radius ``R_j`` about the copies ``lambda_j - i h w1``, for any truncation."""
    import scipy.sparse as sp

    n, w = system.n, system.omega
    Tq, Tv = sp.diags_array(1.0 / avg.sq), sp.diags_array(1.0 / avg.sv)
    Wr = avg.W[:, modes].conj().T  # rows of the modal transform
    out = np.zeros(len(modes))
    for k in system.coefficient_harmonics:
        Kk = sp.csr_array(Tv @ sp.csr_array(system.K[k]) @ Tq) if k in system.K else None
        Dk = sp.csr_array(Tv @ sp.csr_array(system.D[k]) @ Tv) if k in system.D else None
        Mk = sp.csr_array(Tv @ sp.csr_array(system.M[k]) @ Tv) if k in system.M else None
        low = Wr[:, n:]  # the couplings act on the v rows
        part = np.zeros((len(modes), 2 * n), dtype=complex)
        if Kk is not None:
            part[:, :n] += np.asarray((Kk.T @ low.T).T)
        if Dk is not None:
            part[:, n:] += np.asarray((Dk.T @ low.T).T)
        if Mk is not None:
            s = avg.lam[modes] - 1j * k * w
            part[:, n:] += s[:, None] * np.asarray((Mk.T @ low.T).T)
        out += np.abs(part @ avg.X).sum(axis=1)
    return out.tolist()


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

    def dense(x: Any) -> np.ndarray:
        return x.toarray() if hasattr(x, "toarray") else np.asarray(x)

    try:
        Minv = np.linalg.inv(dense(M0))
    except np.linalg.LinAlgError:
        return float("nan"), float("inf")
    if not np.all(np.isfinite(Minv)) or np.linalg.cond(dense(M0)) > 1e12:
        return float("nan"), float("inf")
    D0 = dense(system.D[0]) if 0 in system.D else np.zeros((n, n))
    value = float(np.trace(Minv @ D0).real)
    second = 0.0
    for k, Mk in system.M.items():
        if k == 0:
            continue
        A = Minv @ dense(Mk)
        term = -np.trace(A @ Minv @ dense(system.D[-k])) if -k in system.D else 0.0
        term = term + np.trace(A @ Minv @ dense(system.M[-k]) @ Minv @ D0)
        second += float(np.real(term))
    return -(value + second), abs(second) + 1e-12 * abs(value)


def _conjugate_index(lam: np.ndarray) -> np.ndarray:
    """For each eigenvalue, the index of its conjugate (itself when real); ``-1`` maps to -1."""
    idx = np.array([int(np.argmin(np.abs(lam - np.conj(x)))) for x in lam], dtype=int)
    return np.append(idx, -1)


class _Shifted:
    """A sparse LU of ``Q(sigma)`` that remembers its (possibly nudged) shift."""

    def __init__(self, lu: Any, sigma: complex) -> None:
        self.lu = lu
        self.sigma = sigma

    def solve(self, b: np.ndarray, trans: str = "N") -> np.ndarray:
        return np.asarray(self.lu.solve(b, trans=trans))


def _factor(hill: LatticeHill, sigma: complex, w: float) -> _Shifted:
    """LU of ``Q(sigma)``; an exactly singular shift is moved slightly."""
    scale = max(abs(sigma), w)
    if abs(sigma) < 1e-9 * w:
        sigma = complex(1e-4 * w, 1e-4 * w)
    for attempt in range(4):
        try:
            return _Shifted(spla.splu(hill.Q(sigma), **SPLU), sigma)
        except RuntimeError:  # exactly singular
            sigma += 1e-7 * scale * (1 + 1j) * 10**attempt
    raise RuntimeError(f"cannot factorize the lattice Hill operator near {sigma}")


def _polish(
    hill: LatticeHill, lam: complex, q: np.ndarray, w: float
) -> tuple[complex, np.ndarray, np.ndarray, np.ndarray]:
    """One LU at the exponent: inverse iteration for the right and left null vectors of
    ``Q(lam)`` and a two-sided Newton (Rayleigh functional) step on ``lam``.

    Returns ``(lam, q, u, P(lam)^H u)``.
    """
    lu = _factor(hill, lam, w)
    dQ = hill.inner.dQ(lam, w)
    q1 = lu.solve(np.asarray(dQ @ q))
    q1 /= np.linalg.norm(q1)
    u = lu.solve(np.asarray(dQ.conj().T @ q1), trans="H")  # a start for the left vector
    u /= np.linalg.norm(u)
    u = lu.solve(np.asarray(dQ.conj().T @ u), trans="H")
    u /= np.linalg.norm(u)
    num = np.vdot(u, hill.Q(lam) @ q1)
    den = np.vdot(u, dQ @ q1)
    if den != 0 and np.isfinite(num / den) and abs(num / den) < 1e-4 * max(abs(lam), w):
        lam = lam - num / den
    P = hill.inner.P(lam, w)
    return complex(lam), q1, u, np.asarray(P.conj().T @ u)


class _Outer:
    """Second-order truncation correction from the harmonics just outside the lattice."""

    def __init__(self, hill: LatticeHill, avg: _Averaged) -> None:
        self.hill = hill
        self.avg = avg
        self.O, self.oi, self.io = hill.outer()
        n = hill.n
        self.Xq = avg.X[:n] / avg.sq[:, None]  # Tq X_top
        self.Wv = avg.W[n:].conj() / avg.sv[:, None]  # Tv-weighted conj(W_bot)

    def estimate(self, lam: complex, q: np.ndarray, u: np.ndarray) -> float:
        hill, n, w = self.hill, self.hill.n, self.hill.w
        if self.O.size == 0:
            return 0.0
        r = np.asarray(self.oi.Q(lam, w) @ q).reshape(self.O.size, n)
        a = np.conj(np.asarray(self.io.Q(lam, w).conj().T @ u)).reshape(self.O.size, n)
        den = np.vdot(u, hill.inner.dQ(lam, w) @ q)
        if den == 0:
            return float("inf")
        s_o = lam + 1j * w * self.O.astype(float)
        if self.avg.modal:
            Ga = a @ self.Xq
            Gr = r @ self.Wv
            with np.errstate(divide="ignore", invalid="ignore"):
                term = -np.sum(Ga * Gr / (self.avg.lam[None, :] - s_o[:, None]))
        else:
            term = self._direct(a, r, s_o)
        val = abs(term / den)
        return float(val) if np.isfinite(val) else float("inf")

    def _direct(self, a: np.ndarray, r: np.ndarray, s_o: np.ndarray) -> complex:
        """Without a complete modal basis (massless DOFs): one LU of ``Q0(s)`` per harmonic."""
        import scipy.sparse as sp

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


def _partner(c: _Candidate, H: np.ndarray, n: int, WB: np.ndarray) -> tuple[int, int]:
    """The most energetic harmonic other than 0 of a representative, and the time-averaged
    mode that dominates the eigenvector there (``(0, -1)`` without one)."""
    nh = H.size
    for i in np.argsort(-c.energy, kind="stable"):
        if H[i] != 0:
            yh = np.concatenate(
                [c.y[i * n : (i + 1) * n], c.y[n * nh + i * n : n * nh + (i + 1) * n]]
            )
            return int(H[i]), int(np.argmax(np.abs(WB @ yh)))
    return 0, -1


def _clusters(lam0: np.ndarray, targets: np.ndarray, w: float) -> list[np.ndarray]:
    """Targets grouped where averaged exponents (nearly) coincide (a double eigenvalue of an
    isotropic rotor): one search must find the exponents of the whole group."""
    out: list[np.ndarray] = []
    used = np.zeros(lam0.size, dtype=bool)
    for j in targets:
        if used[j]:
            continue
        near = targets[np.abs(lam0[targets] - lam0[j]) <= CLUSTER_TOL * max(abs(lam0[j]), w)]
        near = near[~used[near]]
        used[near] = True
        out.append(near)
    return out


def _count(kept: list[tuple[_Candidate, bool]]) -> int:
    return sum(2 if conj_too else 1 for _, conj_too in kept)


def _select(
    pool: list[_Candidate],
    quotas: dict[int, int],
    w: float,
    nh: int,
    share: Any = None,
) -> list[tuple[_Candidate, bool]]:
    """Representatives, best centred first, each standing for one cluster of targets.

    A candidate is skipped when it is a copy of an accounted exponent (``lambda + i h w1``
    with ``h`` the shift between their most energetic harmonics), when it has the same value
    as accounted ones and its eigenvector lies in their span (the same exponent found again;
    a multiple exponent has independent eigenvectors and counts once per dimension), or
    when every cluster it can stand for is full (so a copy that escaped recognition cannot
    take the place of another mode's exponent). Returns ``(candidate,
    conjugate_is_another_exponent)`` pairs.
    """
    order = sorted(range(len(pool)), key=lambda i: (pool[i].centroid, pool[i].edge))
    left = dict(quotas)
    kept: list[tuple[_Candidate, bool]] = []
    # (lambda, top harmonics, unit eigenvector, slack) of every accounted exponent
    known: list[tuple[complex, tuple[int, int], np.ndarray, float]] = []
    for i in order:
        if not any(v > 0 for v in left.values()):
            break
        c = pool[i]
        home = [f for f in c.families if left.get(f, 0) > 0]
        if not home:
            continue
        if any(_copy_of(c, lam, top, w, slack=sl) for lam, top, _, sl in known):
            continue
        same = [v for lam, _, v, sl in known if abs(c.lam - lam) <= _tol(c, lam, w) + sl]
        y = c.y / np.linalg.norm(c.y)
        if same:
            sv = np.linalg.svd(np.column_stack([*same, y]), compute_uv=False)
            if sv[-1] <= DEPENDENT * sv[0]:
                continue
        mirrored = (-c.top[0], -c.top[1])
        selfconj = _copy_of(c, np.conj(c.lam), mirrored, w, allow_zero=True)
        kept.append((c, not selfconj))
        known.append((c.lam, c.top, y, c.slack))
        left[home[0]] -= 1
        c.home = home[0]
        if not selfconj:
            known.append((np.conj(c.lam), mirrored, _mirror(y, nh), c.slack))
            # the conjugate counts for the same cluster, or for another one with room
            spare = [f for f in home if left.get(f, 0) > 0]
            if spare:
                left[spare[0]] -= 1
    if share is not None:
        _fill(pool, left, kept, known, w, share)
    return kept


def _fill(
    pool: list[_Candidate],
    left: dict[int, int],
    kept: list[tuple[_Candidate, bool]],
    known: list[tuple[complex, tuple[int, int], np.ndarray, float]],
    w: float,
    share: Any,
) -> None:
    """Clusters still without their exponents (strongly mixed modes whose copies the copy
    test cannot tell apart at this truncation) take, from their own search, the candidate
    whose eigenvector carries most of the cluster's modes summed over all harmonics
    (``share(candidate, cluster)``), not the same eigenpair as an accounted one."""
    for cid, room in left.items():
        while room > 0:
            own = [
                c
                for c in pool
                if c.search == cid
                and not any(abs(c.lam - lam) <= _tol(c, lam, w) + sl for lam, _, _, sl in known)
            ]
            if not own:
                break
            best = max(own, key=lambda c: share(c, cid) / (1.0 + c.centroid))
            selfconj = _copy_of(
                best, np.conj(best.lam), (-best.top[0], -best.top[1]), w, allow_zero=True
            )
            kept.append((best, not selfconj))
            known.append((best.lam, best.top, best.y / np.linalg.norm(best.y), best.slack))
            if not selfconj:
                known.append((np.conj(best.lam), best.top, best.y, best.slack))
            best.forced = True
            best.home = cid
            room -= 1 if selfconj else 2
        left[cid] = room


def _mirror(y: np.ndarray, nh: int) -> np.ndarray:
    """The eigenvector of the conjugate exponent: ``conj(y_{-h})`` (the lattice is symmetric
    and sorted, so harmonic ``-h`` sits at the reversed position)."""
    return np.conj(y.reshape(2, nh, -1)[:, ::-1, :].ravel())


def _tol(c: _Candidate, lam: complex, w: float) -> float:
    scale = max(abs(c.lam), abs(lam), w)
    return 1e-8 * scale + 1e-3 * np.sqrt(c.edge) * scale + c.slack


def _copy_of(
    c: _Candidate,
    lam: complex,
    top: tuple[int, int],
    w: float,
    allow_zero: bool = False,
    slack: float = 0.0,
) -> bool:
    """True when ``c.lam = lam + i h w`` for a shift ``h`` between their energetic harmonics."""
    tol = _tol(c, lam, w) + slack
    for tk in top:
        for tc in c.top:
            h = tk - tc
            if h == 0 and not allow_zero:
                continue
            if abs(c.lam - lam - 1j * h * w) <= tol:
                return True
    return False
