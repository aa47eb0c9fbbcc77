"""The lattice search: shift-invert Arnoldi near every cluster of time-averaged modes
(docs/stability.md).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..harmonics.hill_lattice import LatticeHill
from ..harmonics.lattice import Lattice
from ..system.periodic import PeriodicSystem
from .averaged import _Averaged
from .checks import _gershgorin, _Outer, _split_gaps, liouville_sum
from .outcome import LatticeExponents
from .result import _EPS, SAFETY, TRUNCATION_SAFETY
from .select import ACCEPT_WEIGHT, CENTRED, CLUSTER_TOL, _Candidate, _clusters, _count, _select

__all__ = ["ARNOLDI_STEPS", "ARNOLDI_TOL", "SPLU", "UNRESOLVED_EDGE", "lattice_exponents"]


#: A representative with more energy than this on the outer shell is not resolved by the
#: truncation: its verdict comes from the Gershgorin discs of its modes.
UNRESOLVED_EDGE = 0.1


#: SuperLU options for the lattice operator. ``Q(sigma)`` is structurally symmetric (harmonic
#: ``m`` couples to ``n`` exactly where ``n`` couples to ``m``), so SuperLU's symmetric mode:
#: minimum degree on ``A + A^T`` and diagonal pivots unless one is below 1 % of its column
#: (threshold partial pivoting). On the gearbox (one thread) this factorizes order 2 (4,410
#: unknowns) in 6.5 ms instead of 8 ms and order 3 (14,994) in 25 ms instead of 80-170 ms,
#: with 2-3x less fill and 2x faster solves than column AMD with a 0.1 threshold; residuals
#: 1e-12 either way. The Newton step on each representative uses Q itself, so the factor's
#: accuracy does not limit the exponents.
SPLU: dict[str, Any] = {
    "permc_spec": "MMD_AT_PLUS_A",
    "diag_pivot_thresh": 0.01,
    "options": {"SymmetricMode": True},
}


#: Arnoldi: checkpoints (basis sizes) and the relative residual of an accepted Ritz pair.
ARNOLDI_STEPS = (10, 16, 24, 36, 54)


ARNOLDI_TOL = 1e-10

#: Checkpoints of a search started from the previous speed's eigenvectors on the same lattice
#: (``same_system=False``): nearly eigenvectors, which four steps usually converge (the
#: gearbox's order-1 Arnoldi time halves). A coarser lattice's vectors are further off on a
#: finer one: those searches keep :data:`ARNOLDI_STEPS`.
WARM_STEPS = (4, *ARNOLDI_STEPS)

#: Tracking (a search continued from the previous speed on the same lattice): each of a
#: cluster's previous representatives is moved by its cluster's averaged shift and polished
#: there (one LU, three solves: no Arnoldi run). Accepted when every one converges to a
#: backward error below this (relative, of the balanced first-order pencil), is centred (or
#: the same off-centre copy as before: :data:`TRACK_DRIFT`) and stands for its cluster only,
#: and together they meet the cluster's quota as distinct exponents (the test a search
#: meets); otherwise the cluster is searched.
TRACK_TOL = 1e-10

#: Polish steps (an LU each) a tracked exponent may take to meet :data:`TRACK_TOL` (the
#: averaged shift predicts the gearbox's exponents to 0.1-4 rad/s from one speed to the next:
#: one step leaves a backward error of 1e-10 to 1e-9 on some).
TRACK_POLISH = 2

#: An off-centre representative (centroid above :data:`~rheolin.floquet.select.CENTRED`: its
#: energy split between harmonic 0 and its neighbours, a mode coupled strongly through the
#: time variation) is tracked as well when it stays the same copy of the same exponent: its
#: centroid moves by at most ``TRACK_DRIFT`` and its real part by at most ``TRACK_DRIFT`` of
#: its distance from the axis (a copy changing places, or a resonance setting in, moves them
#: faster; the cluster is then searched). Copies of one exponent share its real part, so the
#: copy kept does not change the verdict; its truncation is judged as a search's would be
#: (unresolved: by the discs or a finer lattice).
TRACK_DRIFT = 0.05

#: Classical Gram-Schmidt is repeated when it cancels more than this fraction of the vector
#: (Daniel, Gragg, Kaufman and Stewart's criterion, 1/sqrt(2)): orthogonal to working
#: precision at half the cost of always orthogonalizing twice.
DGKS = 0.7071


#: A warm-started search ends when every coarse eigenvector has a converged Ritz vector at
#: least this close (|cos| of the angle between them).
WARM_OVERLAP = 0.5

#: A cold search that cannot meet its quota with centred copies ends at the first checkpoint
#: from this one (24 steps) where its cluster's exponents are converged and the best centroid
#: among them improved by less than ``STALL_GAIN`` since the previous checkpoint (on the
#: gearbox such searches ran to 54 steps: 0.70 of 0.93 s of Arnoldi at order 2).
STALL_CHECKPOINT = 3
STALL_GAIN = 0.1


def lattice_exponents(
    system: PeriodicSystem,
    lattice: Lattice,
    *,
    near: np.ndarray | None = None,
    start: LatticeExponents | None = None,
    same_system: bool = True,
    coarse: LatticeExponents | None = None,
    defer_truncation: bool = False,
) -> LatticeExponents:
    """Representatives of the Floquet exponents of ``system`` on ``lattice``.

    See the module docstring for the method. ``near`` restricts the search to the
    time-averaged modes nearest these values (for tracking one exponent across speeds); the
    result is then partial (``expected`` is the number of those modes). ``start``: the
    representatives of a coarser lattice of the same system; each cluster's search starts from
    its eigenvectors there (a few Arnoldi steps instead of a full run). ``same_system=False``:
    ``start`` is of a nearby system (the previous speed of a sweep, on a lattice with the same
    or fewer harmonics): only its eigenvectors are used, for the clusters whose time-averaged
    exponents have not moved by more than ``CLUSTER_TOL`` (the others start cold).
    ``coarse`` (with such a ``start``): the representatives of a coarser lattice of this
    system, for the clusters ``start`` does not cover (a finer lattice's confirmation over a
    sweep: the previous speed's fine vectors first, this speed's coarse ones otherwise).
    ``defer_truncation``: the truncation estimates are left to the result's ``settle(rows)``
    (a confirmation keeps only some of the finer lattice's exponents; NaN until settled).
    """
    t0 = time.perf_counter()
    n, w = system.n, system.omega
    H = lattice.indices
    nh = H.size
    if 0 not in set(H.tolist()):
        raise ValueError("the lattice must contain harmonic 0")
    # of this system: its averaged modes and Liouville sum hold here too
    same = start if same_system else coarse
    avg = same.modes if same is not None and same.modes is not None else _Averaged(system)
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
        warm, at = _warm_start(
            start,
            H,
            n,
            sigma,
            w,
            rng,
            resolved=coarse is not None,
            rows=None if same_system else previous(cid),
        )
        steps = WARM_STEPS if warm is not None and not same_system else ARNOLDI_STEPS
        if warm is None and not same_system:
            warm, at = _warm_start(coarse, H, n, sigma, w, rng)
        if warm is not None:
            sigma = at  # where the coarse exponents are: their continuations converge first
            warm_starts.append(cid)
        t1 = time.perf_counter()
        lu = _factor(hill, sigma, w, many=steps is ARNOLDI_STEPS)
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
        if warm is not None:
            v0 = warm.sum(axis=1) + 1e-2 * v0 / np.linalg.norm(v0)
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
            # the quota is judged jointly with the clusters already searched that these
            # candidates can also stand for: two close modes (x and y on anisotropic
            # bearings) must not both be satisfied by the one exponent nearest them, or a
            # parametric exponent between them (a principal resonance) is never sought
            joint = {f for c in mine for f in c.families if f in done} - {cid}
            quota = {cid: need, **{f: done[f] for f in joint}}
            cands = mine + [
                c for c in pool if c.centroid <= CENTRED and joint.intersection(c.families)
            ]
            satisfied[0] = _count(_select(cands, quota, w, nh)) >= sum(quota.values())
            if not satisfied[0] and warm is None:
                # a cold search whose cluster's exponents are all converged but none is
                # centred (energy out at the lattice edge: unresolved, settled on a finer
                # lattice) ends when the best-centred copy stops improving: more steps find
                # copies further from the shift, not a better one
                ours = [c.centroid for c in found_here if cid in c.families]
                best = min(ours, default=np.inf)
                stall[0] += 1
                stalled = (
                    stall[0] >= STALL_CHECKPOINT
                    and len(ours) >= need
                    and best >= (1.0 - STALL_GAIN) * stall[1]
                )
                stall[1] = min(stall[1], best)
                return stalled
            if not satisfied[0] and warm is not None:
                # a warm start ends when each coarse eigenvector has its continuation: a
                # converged Ritz vector close to it (a mixed cluster's quota may never be
                # met by centred copies)
                unit = vecs / np.linalg.norm(vecs, axis=0)
                overlap = np.abs(warm_unit.conj().T @ unit).max(axis=1)
                return bool(np.all(overlap >= WARM_OVERLAP))
            return satisfied[0]

        satisfied = [False]
        stall = [0, np.inf]  # checkpoints seen, best centroid of the cluster's candidates
        if warm is not None:
            warm_unit = warm / np.linalg.norm(warm, axis=0)
        _arnoldi(apply, v0, accept, steps=steps, tol=ARNOLDI_TOL)
        arnoldi_seconds += time.perf_counter() - t2
        for c in found_here:
            c.search = cid
        if satisfied[0]:
            done[cid] = need
        else:
            short.append(sigma)
        return found_here

    normA, normB = _pencil_norms(hill, avg.sq, avg.sv)

    def first_order(q: np.ndarray, lam: complex) -> np.ndarray:
        """The balanced first-order right vector ``(q, s q)`` of ``q``."""
        return np.concatenate([q * sq_rep, hill.s(lam) * q * sv_rep])

    def residual(q: np.ndarray, lam: complex) -> float:
        """``||Q(lam) q||`` on the balanced rows (the first-order pencil's residual)."""
        return float(np.linalg.norm(np.asarray(hill.Q(lam) @ q) / sv_rep))

    def track(cid: int) -> list[_Candidate] | None:
        """The cluster's exponents continued from the previous speed's (None: not possible
        or not accepted; the cluster is then searched)."""
        if start is None or same_system or not np.array_equal(start.indices, H):
            return None
        mine, moved = previous(cid)
        # only representatives standing for this cluster alone (as its search's would be): a
        # mixed one is searched again
        if not mine or any(len(start.related[i]) != 1 for i in mine):
            return None
        # a Newton step may go a quarter of the way to the nearest other averaged exponent
        others = np.ones(lam0.size, dtype=bool)
        others[clusters[cid]] = False
        sigma = complex(np.mean(lam0[clusters[cid]]))
        reach = 0.25 * float(np.min(np.abs(lam0[others] - sigma), initial=np.inf))
        found: list[_Candidate] = []
        for i in mine:
            vec = start.vectors[i]
            assert vec is not None
            q1, _ = to_unbalanced(vec)
            # the exponent moves with its averaged one: by the rate seen last time (the
            # secant dlambda / dsigma of the previous step), else one to one
            rate = start.rate[i] if start.rate.size == start.exponents.size else np.nan
            rate = complex(rate) if np.isfinite(rate) else 1.0
            lam_t = complex(start.exponents[i] + rate * moved)
            for _ in range(TRACK_POLISH):
                lam_t, q1, u, yq = _polish(hill, lam_t, q1, w, step=reach)
                xb = first_order(q1, lam_t)
                res = residual(q1, lam_t)
                scale = (normA + abs(lam_t) * normB) * float(np.linalg.norm(xb))
                if not np.isfinite(lam_t) or res <= TRACK_TOL * scale:
                    break
            if not (np.isfinite(lam_t) and res <= TRACK_TOL * scale):
                return None
            c = candidate(xb, lam_t, -1)
            if tuple(c.families) != (cid,):
                return None
            was, before = float(start.centroid[i]), complex(start.exponents[i])
            if (was > CENTRED or c.centroid > CENTRED) and not (
                abs(c.centroid - was) <= TRACK_DRIFT
                and abs(lam_t.real - before.real) <= TRACK_DRIFT * abs(before.real)
            ):
                return None  # off centre: only the same copy, moving slowly
            c.search = cid
            c.polished = (lam_t, q1, u, yq, res)
            if moved != 0:
                c.rate = complex((lam_t - start.exponents[i]) / moved)
            found.append(c)
        if _count(_select(found, {cid: quotas[cid]}, w, nh)) < quotas[cid]:
            return None
        tracked.append(cid)
        done[cid] = quotas[cid]
        return found

    matched: dict[int, tuple[list[int], complex]] = {}

    def previous(cid: int) -> tuple[list[int], complex]:
        if cid not in matched:
            matched[cid] = (
                _previous_rows(start, lam0, clusters[cid], w)
                if start is not None and not same_system
                else ([], 0j)
            )
        return matched[cid]

    def find(cid: int) -> list[_Candidate]:
        got = track(cid)
        return got if got is not None else search(cid)

    tracked: list[int] = []
    short: list[complex] = []
    warm_starts: list[int] = []
    done: dict[int, int] = {}  # clusters whose search met its quota: their quotas
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
            pool.extend(find(cid))
    # a certified cluster may still hold the leading exponent (its disc reaches right of
    # every computed one): search those too, rightmost disc first, so that the largest real
    # part reported is an exponent's, not the best of the rest
    full = {
        i: sum(1 if abs(lam0[c].imag) <= 1e-9 * scale0[c] else 2 for c in cl)
        for i, cl in enumerate(clusters)
    }
    right = {cid: float(np.max(lam0[clusters[cid]].real + discs[clusters[cid]])) for cid in skipped}
    for cid in sorted(skipped, key=lambda c: -right[c]):
        lead = max((c.lam.real for c in pool), default=-np.inf)
        if right[cid] <= lead:
            break
        skipped.remove(cid)
        quotas[cid] = full[cid]
        pool.extend(find(cid))

    expected = int(sum(quotas.values()))
    reps = _select(pool, quotas, w, nh, share=share)
    # left eigenvectors, error bounds and truncation estimates of the representatives
    Mb = sp.diags_array(1.0 / sv_rep) @ Mconv @ sp.diags_array(1.0 / sv_rep)

    def B_b(xb: np.ndarray) -> np.ndarray:  # the balanced first-order B times xb
        return np.concatenate([xb[: n * nh], Mb @ xb[n * nh :]])

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
    outer = _Outer(hill, avg) if nh > 0 else None
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
                radius.update(zip(need_r, _gershgorin(system, avg, need_r), strict=True))
            ok = bool(modes.size) and all(lam0[m].real + radius[int(m)] < 0 for m in modes)
        disc = max((radius[int(m)] for m in modes), default=0.0) if unresolved and ok else 0.0
        if c.polished is not None:  # tracked: polished already, its residual known
            lam_c, xq, u, yq, res = c.polished
        else:
            xq, _ = to_unbalanced(c.y)
            lam_c, xq, u, yq = _polish(hill, c.lam, xq, w)
            # the pair's own residual enters its bound (a Ritz pair accepted wrongly then
            # gets a wide tolerance, never a confident verdict)
            res = residual(xq, lam_c)
        c.lam = lam_c
        # first-order vectors: right (q, s q), left (P^H u, u); balanced: R^-1 x, L^-1 y
        xb = first_order(xq, lam_c)
        yb = np.concatenate([yq / sq_rep, u * sv_rep])
        denom = abs(np.vdot(yb, B_b(xb)))
        nx, ny = np.linalg.norm(xb), np.linalg.norm(yb)
        # first order in the backward error: rounding's, or a tracked pair's residual
        err = max(_EPS * (normA + abs(lam_c) * normB) * nx, res)
        bound = err * ny / max(denom, np.finfo(float).tiny)
        if outer is None:
            tau = 0.0
        elif defer_truncation:
            tau = float("nan")
            deferred.append((lam_c, xq, u))
        else:
            tau = outer.estimate(lam_c, xq, u)
        part = _partner(c, H, n, avg.WB, conj_index)
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
    info = {
        "lattice_size": nh,
        "lattice_order": lattice.order,
        "hill_size": size,
        "shifts": len(shifts),
        "lu_seconds": lu_seconds,
        "arnoldi_seconds": arnoldi_seconds,
        "seconds": time.perf_counter() - t0,
        "short_searches": [complex(x) for x in short],
        "warm_starts": len(warm_starts),
        "tracked": len(tracked),
        "certified_modes": np.concatenate(
            [lam0[clusters[c]] for c in skipped] + [np.zeros(0, complex)]
        ),
        "certified_radii": np.concatenate([discs[clusters[c]] for c in skipped] + [np.zeros(0)]),
    }
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
        liouville=same.liouville if same is not None else liouville_sum(system),
        info=info,
        vectors=vectors,
        indices=H,
        modes=avg,
        rate=np.array(rates, dtype=complex),
    )
    if deferred and outer is not None:
        result.settle = _settler(outer, deferred)
    return result


def _settler(outer: _Outer, deferred: list[tuple[complex, np.ndarray, np.ndarray]]) -> Any:
    """``(out, rows) -> None``: the truncation estimates of those rows of ``out``, found by
    their exponent (a representative's row and its conjugate's share one estimate, computed
    once), so that the rows may have moved since (a confirmation keeps some coarse rows and
    appends finer ones). (The result is an argument, not captured: a result holding a closure
    over itself is a reference cycle, which kept the finer lattices' operators and PARDISO
    factors alive until a full garbage collection: 2 GB per worker over a run-up.)"""
    requests = {complex(lam): (lam, q, u) for lam, q, u in deferred}
    known: dict[complex, float] = {}

    def settle(out: LatticeExponents, rows: np.ndarray) -> None:
        for row in np.asarray(rows, dtype=int):
            if not np.isnan(out.truncation[row]):
                continue
            z = complex(out.exponents[row])
            key = z if z in requests else complex(np.conj(z))
            if key not in requests:
                continue  # not this lattice's exponent
            if key not in known:
                known[key] = outer.estimate(*requests[key])
            tau = known[key]
            out.truncation[row] = tau
            out.uncertainty[row] = max(out.uncertainty[row], TRUNCATION_SAFETY * tau)

    return settle


def _pencil_norms(hill: LatticeHill, sq: np.ndarray, sv: np.ndarray) -> tuple[float, float]:
    """1-norms of the balanced first-order Hill pencil ``(A, B)`` of
    :func:`~rheolin.harmonics.hill_pencil` on the lattice, from the couplings of ``hill`` (column
    sums; without building the pencil, which cost 0.15 s at order 3 on the gearbox).

    Columns of harmonic ``h``: ``q`` columns ``|w h| + sum |K| / (s_v,row s_q,col)``, ``v``
    columns ``s_q / s_v + sum |D + i h w M| / (s_v,row s_v,col)``; ``B``: 1 on ``q``
    columns and ``sum |M| / (s_v,row s_v,col)`` on ``v`` columns.
    """
    inner, n, w = hill.inner, hill.n, hill.w
    size = hill.size
    dof_r, dof_c = inner.rows % n, inner.cols % n
    col_q = np.abs(w * np.repeat(hill.H.astype(float), n))
    col_v = np.tile(sq / sv, hill.H.size)
    b_v: np.ndarray = np.zeros(size)
    if inner.nnz:
        col_q = col_q + np.bincount(
            inner.cols, np.abs(inner.K) / (sv[dof_r] * sq[dof_c]), minlength=size
        )
        col_v = col_v + np.bincount(
            inner.cols,
            np.abs(inner.D + 1j * w * inner.col_h * inner.M) / (sv[dof_r] * sv[dof_c]),
            minlength=size,
        )
        b_v = np.bincount(inner.cols, np.abs(inner.M) / (sv[dof_r] * sv[dof_c]), minlength=size)
    normA = float(max(col_q.max(initial=0.0), col_v.max(initial=0.0)))
    normB = float(max(1.0, b_v.max(initial=0.0)))
    return normA, normB


def _warm_start(
    start: LatticeExponents | None,
    H: np.ndarray,
    n: int,
    sigma: complex,
    w: float,
    rng: np.random.Generator,
    resolved: bool = False,
    rows: tuple[list[int], complex] | None = None,
) -> tuple[np.ndarray | None, complex]:
    """The coarse eigenvectors of the cluster centred at ``sigma``, moved onto the harmonics
    ``H`` with random weights, one per column, and the mean of their exponents (None: none
    known). ``rows``: the rows of ``start`` standing for this cluster and the shift of its
    averaged exponents since (another system's start, :func:`_previous_rows`); else those
    whose cluster centre is ``sigma`` (the same system's)."""
    if start is None or not start.vectors:
        return None, sigma
    tol = CLUSTER_TOL * max(abs(sigma), w)
    Hc = start.indices
    pos = np.searchsorted(H, Hc)
    if np.any(pos >= H.size) or np.any(H[np.minimum(pos, H.size - 1)] != Hc):
        return None, sigma  # not a sub-lattice
    nh, nc = H.size, Hc.size
    cols = (pos[:, None] * n + np.arange(n)).ravel()
    if rows is not None:
        candidates, moved = rows
    else:
        candidates = [i for i, z in enumerate(start.centre) if abs(z - sigma) <= tol]
        moved = 0j
    mine = [
        i
        for i in candidates
        if start.vectors[i] is not None and not (resolved and start.unresolved[i])
    ]
    if not mine:
        return None, sigma
    picked = [v for v in (start.vectors[i] for i in mine) if v is not None]
    out = np.zeros((2 * n * nh, len(picked)), dtype=complex)
    for j, v in enumerate(picked):
        c = complex(rng.standard_normal(), rng.standard_normal())
        out[cols, j] = c * v[: n * nc]
        out[n * nh + cols, j] = c * v[n * nc :]
    return out / np.linalg.norm(out), complex(np.mean(start.exponents[mine])) + moved


def _previous_rows(
    start: LatticeExponents, lam0: np.ndarray, members: np.ndarray, w: float
) -> tuple[list[int], complex]:
    """The rows of ``start`` (a nearby system's search: the previous speed) standing for the
    cluster of averaged exponents ``lam0[members]`` (all of them in ``lam0``, conjugates
    included), and how far the cluster's centre moved since (``([], 0)``: no unambiguous
    match).

    The previous cluster is the one whose centre is nearest this centre, when it moved by
    less than ``CLUSTER_TOL`` (relative), or by less than half the distance to any other
    averaged exponent and less than the previous centre's distance to any of them (no other
    exponent can have come from there).
    """
    have = [i for i, v in enumerate(start.vectors) if v is not None]
    if not have:
        return [], 0j
    sigma = complex(np.mean(lam0[members]))
    prev = np.unique(start.centre[have])
    prev = prev[np.isfinite(prev)]
    if not prev.size:
        return [], 0j
    j = int(np.argmin(np.abs(prev - sigma)))
    zp, d = complex(prev[j]), float(np.abs(prev[j] - sigma))
    if d > CLUSTER_TOL * max(abs(sigma), w):
        # every other averaged exponent (the conjugates are among them)
        others = np.ones(lam0.size, dtype=bool)
        others[members] = False
        rest = lam0[others]
        gap = float(np.min(np.abs(rest - sigma))) if rest.size else np.inf
        to_prev = float(np.min(np.abs(rest - zp))) if rest.size else np.inf
        if not (d < 0.5 * gap and d < to_prev):
            return [], 0j
    return [i for i in have if start.centre[i] == zp], sigma - zp


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
        before = float(np.linalg.norm(wv))
        h = np.conj(basis @ np.conj(wv))
        wv = wv - h @ basis
        beta = float(np.linalg.norm(wv))
        if beta < DGKS * before:  # cancellation: a second Gram-Schmidt pass (DGKS criterion)
            h2 = np.conj(basis @ np.conj(wv))
            wv = wv - h2 @ basis
            h = h + h2
            beta = float(np.linalg.norm(wv))
        Hm[: j + 1, j] = h
        Hm[j + 1, j] = beta
        m = j + 1
        ended = beta <= 1e-14 * float(np.abs(Hm[: j + 2, : j + 1]).max())
        if not ended:
            V[j + 1] = wv / beta
        if m in checkpoints or ended or m == m_max:
            theta, Svec = np.linalg.eig(Hm[:m, :m])
            # the residual of each Ritz pair, also at a breakdown: "ended" is relative to the
            # largest Ritz value, and a shift on an exponent (a tracked start) makes that one
            # huge while the far pairs are not converged at all
            res = beta * np.abs(Svec[-1, :])
            good = res <= tol * np.abs(theta)
            if good.any():
                vecs = V[:m].T @ Svec[:, good]
                if accept(theta[good], vecs) or ended:
                    return
            if ended:
                return


class _Shifted:
    """A sparse LU of ``Q(sigma)`` that remembers its (possibly nudged) shift."""

    def __init__(self, lu: Any, sigma: complex, Q: Any = None) -> None:
        self.lu = lu
        self.sigma = sigma
        self.Q = Q  # the matrix factorized

    def solve(self, b: np.ndarray, trans: str = "N") -> np.ndarray:
        return np.asarray(self.lu.solve(b, trans=trans))


#: Above these many unknowns the lattice operator is factorized by MKL PARDISO (where
#: installed; the analysis is made once per lattice and serves every shift), for a factor
#: used a few times (the polish, a warm-started Arnoldi run) and one used for a whole cold
#: Arnoldi run. On the gearbox (one thread; PARDISO refining only after perturbed pivots,
#: SuperLU in symmetric mode), factor / solve: order 1 (882 unknowns) 0.33 / 0.085 ms against
#: 0.40 / 0.040 ms; order 2 (4,410) 1.9-2.7 / 0.4-0.5 ms against 2.4-7 / 0.2-0.25 ms (SuperLU's
#: pivoting varies with the shift: 4.3 ms on average over a gearbox verdict, whose order-2
#: confirmation took 0.12 s less per speed with PARDISO); order 3 (14,994) 10-11.5 / 1.4-2.1 ms
#: against 18-40 / 1.0-1.2 ms; order 4 (41,454) 74 / 5.5 ms against 550 / 11 ms. A cold Arnoldi
#: run (up to 54 steps) favours SuperLU's solves up to order 3.
PARDISO_ABOVE = 2000
PARDISO_ABOVE_ARNOLDI = 30000


def _pardiso_factor(hill: LatticeHill, Q: Any) -> Any | None:
    """A PARDISO factor of ``Q`` (None: not installed, or no free slot).

    The analysis is kept on ``hill`` (one lattice at one speed), not across calls: MKL
    PARDISO crashes when its thread count changes between the analysis and a factorization
    (``threadpool_limits`` entered anew by the next call).
    """
    from ..linalg.direct import available_backends, csc_pattern_key

    if "pardiso" not in available_backends():
        return None
    from ..linalg.direct.pardiso import PardisoBackend

    Q = sp.csc_array(Q)
    Q.sort_indices()
    key = csc_pattern_key(Q.indptr, Q.indices)
    cached = getattr(hill, "_pardiso", None)
    if cached is None or cached[0] != key:
        backend = PardisoBackend(
            Q.indptr.astype(np.int64), Q.indices.astype(np.int64), True, slots=16, refinement=0
        )
        hill._pardiso = cached = (key, backend)  # type: ignore[attr-defined]
    try:
        return cached[1].factor(Q.data)
    except RuntimeError as exc:
        if "slots" in str(exc):
            return None
        raise


def _factor(hill: LatticeHill, sigma: complex, w: float, *, many: bool = False) -> _Shifted:
    """LU of ``Q(sigma)``; an exactly singular shift is moved slightly. ``many``: the factor
    will serve many solves (an Arnoldi run), which changes the fastest backend."""
    scale = max(abs(sigma), w)
    if abs(sigma) < 1e-9 * w:
        sigma = complex(1e-4 * w, 1e-4 * w)
    for attempt in range(4):
        Q = hill.Q(sigma)
        try:
            if Q.shape[0] > (PARDISO_ABOVE_ARNOLDI if many else PARDISO_ABOVE):
                f = _pardiso_factor(hill, Q)
                if f is not None:
                    return _Shifted(f, sigma, Q)
            return _Shifted(spla.splu(Q, **SPLU), sigma, Q)
        except RuntimeError:  # exactly singular
            sigma += 1e-7 * scale * (1 + 1j) * 10**attempt
    raise RuntimeError(f"cannot factorize the lattice Hill operator near {sigma}")


def _polish(
    hill: LatticeHill, lam: complex, q: np.ndarray, w: float, step: float | None = None
) -> tuple[complex, np.ndarray, np.ndarray, np.ndarray]:
    """One LU at the exponent: inverse iteration for the right and left null vectors of
    ``Q(lam)`` and a two-sided Newton (Rayleigh functional) step on ``lam``.

    (Reusing the search's factor at ``sigma`` instead, with shift-invert steps of the
    first-order pencil, gave the same vectors to 1e-15 but was slower on the gearbox: 5-13
    steps where one LU and three solves do, and the kept factors cost memory.)

    The Newton step is taken when it is below ``step`` (default ``1e-4 max(|lam|, w1)``: a
    polish of a converged pair; a tracked exponent allows larger ones).

    Returns ``(lam, q, u, P(lam)^H u)``.
    """
    lu = _factor(hill, lam, w)
    dQ = hill.inner.dQ(lam, w)
    dQH = dQ.conj().T
    q1 = lu.solve(np.asarray(dQ @ q))
    q1 /= np.linalg.norm(q1)
    u = lu.solve(np.asarray(dQH @ q1), trans="H")  # a start for the left vector
    u /= np.linalg.norm(u)
    u = lu.solve(np.asarray(dQH @ u), trans="H")
    u /= np.linalg.norm(u)
    Q = lu.Q if lu.sigma == lam else hill.Q(lam)
    num = np.vdot(u, Q @ q1)
    den = np.vdot(u, dQ @ q1)
    limit = 1e-4 * max(abs(lam), w) if step is None else step
    if den != 0 and np.isfinite(num / den) and abs(num / den) < limit:
        lam = lam - num / den
    P = hill.inner.P(lam, w)
    return complex(lam), q1, u, np.conj(np.asarray(P.T @ np.conj(u)))


def _partner(
    c: _Candidate, H: np.ndarray, n: int, WB: np.ndarray, conj: np.ndarray
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

    def mode_at(i: int) -> int:
        yh = np.concatenate([c.y[i * n : (i + 1) * n], c.y[n * nh + i * n : n * nh + (i + 1) * n]])
        return int(np.argmax(np.abs(WB @ yh)))

    modes = {i: mode_at(i) for i in big}
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
