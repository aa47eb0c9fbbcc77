"""The lattice search: shift-invert Arnoldi near every cluster of time-averaged modes
(docs/stability.md), run by :class:`LatticeSearch` in named steps. The kernel (factors,
Arnoldi, polish) is :mod:`~rheolin.floquet.shift_invert`, the start vectors from a previous
speed come from :mod:`~rheolin.floquet.continuation`, the result is assembled by
:mod:`~rheolin.floquet.representatives`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import numpy as np

from ..harmonics.hill_lattice import LatticeHill
from ..harmonics.lattice import Lattice
from ..system.periodic import PeriodicSystem
from .averaged import Averaged
from .checks import liouville_sum
from .continuation import (
    TRACK_DRIFT,
    TRACK_POLISH,
    TRACK_TOL,
    WARM_OVERLAP,
    previous_rows,
    warm_start,
)
from .outcome import LatticeExponents
from .representatives import lattice_result
from .resonance import averaged_modes
from .result import SAFETY
from .select import ACCEPT_WEIGHT, CENTRED, Candidate, clusters, count, select, targets
from .shift_invert import (
    BalancedPencil,
    ShiftInvert,
    arnoldi,
    factor,
    harmonic_block,
    harmonic_energy,
    polish,
)

__all__ = ["ARNOLDI_STEPS", "ARNOLDI_TOL", "LatticeSearch", "lattice_exponents"]


#: Arnoldi: checkpoints (basis sizes) and the relative residual of an accepted Ritz pair.
ARNOLDI_STEPS = (10, 16, 24, 36, 54)


ARNOLDI_TOL = 1e-10

#: Checkpoints of a search started from the previous speed's eigenvectors on the same lattice
#: (``same_system=False``): nearly eigenvectors, which four steps usually converge. A coarser
#: lattice's vectors are further off on a finer one: those searches keep
#: :data:`ARNOLDI_STEPS` (bench/stability.py, design notes).
WARM_STEPS = (4, *ARNOLDI_STEPS)

#: Checkpoints of a search started from a coarser lattice's eigenvectors (a confirmation): on
#: the gearbox, of those that ended at the first cold checkpoint (10 steps), a third end at 6
#: and nearly half at 8 (bench/stability.py, design notes).
CONFIRM_STEPS = (6, 8, *ARNOLDI_STEPS)

#: A cold search that cannot meet its quota with centred copies ends at the first checkpoint
#: from this one (24 steps) where its cluster's exponents are converged and the best centroid
#: among them improved by less than ``STALL_GAIN`` since the previous checkpoint: more steps
#: find copies further from the shift, not a better one (bench/stability.py, design notes).
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
    modes: Averaged | None = None,
    room: int | None = None,
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
    ``modes``: the time-averaged modes to start from (a band of a large model,
    :func:`~rheolin.floquet.band.band_modes`); default all of them, or ``start``'s.
    ``room``: the memory [bytes] the search may use (None: not checked); it is refused
    (:class:`~rheolin.budget.MemoryBudgetError`) before its first factor when its estimate
    for the clusters it has to search exceeds it, and as soon as the eigenvectors it has
    found do (:class:`LatticeSearch`).
    """
    search = LatticeSearch(
        system,
        lattice,
        near=near,
        start=start,
        same_system=same_system,
        coarse=coarse,
        defer_truncation=defer_truncation,
        modes=modes,
        room=room,
    )
    return search.run()


@dataclass
class _Run:
    """What the checkpoints of one cluster's Arnoldi run have seen."""

    cid: int
    need: int  # the cluster's quota
    sigma: complex  # the shift
    shift: int  # its index in ``LatticeSearch.shifts``
    warm: np.ndarray | None  # the start vectors of a warm start
    warm_unit: np.ndarray | None = None
    found: list[Candidate] = field(default_factory=list)  # the last checkpoint's candidates
    satisfied: bool = False  # the quota met (jointly with the linked clusters)
    checkpoints: int = 0  # seen without meeting the quota (a cold start)
    best: float = np.inf  # the best centroid among the cluster's candidates so far


class LatticeSearch:
    """One lattice search (see :func:`lattice_exponents` for the arguments).

    Its state: the averaged modes ``avg`` and their ``clusters`` (each with its ``quotas``
    entry: its exponents, conjugates included; ``family_of`` maps a mode to its cluster),
    the Gershgorin ``discs`` and the clusters ``skipped`` by them, the candidates ``pool``,
    the clusters ``done`` (quota met), ``tracked``, ``warm_starts``, the ``shifts`` and
    ``short`` searches, and the timers.

    Memory: with a ``room`` [bytes], the search is refused before its first factor when the
    estimate of :func:`~rheolin.floquet.footprint.lattice_memory` for the clusters it has to
    search (known once the Gershgorin discs have certified the others) exceeds it, and
    stopped as soon as its operator's estimate and the eigenvectors found so far do (a
    search whose clusters find many more candidates than usual): a
    :class:`~rheolin.budget.MemoryBudgetError`, never the operating system's kill.
    """

    def __init__(
        self,
        system: PeriodicSystem,
        lattice: Lattice,
        *,
        near: np.ndarray | None = None,
        start: LatticeExponents | None = None,
        same_system: bool = True,
        coarse: LatticeExponents | None = None,
        defer_truncation: bool = False,
        modes: Averaged | None = None,
        room: int | None = None,
    ) -> None:
        self.t0 = time.perf_counter()
        self.room = room
        self._base: int | None = None  # the operator's estimate (without the vectors found)
        self.system, self.lattice = system, lattice
        self.n, self.w = system.n, system.omega
        self.H = lattice.indices
        self.nh = self.H.size
        if 0 not in set(self.H.tolist()):
            raise ValueError("the lattice must contain harmonic 0")
        self.near, self.start, self.coarse = near, start, coarse
        self.same_system, self.defer_truncation = same_system, defer_truncation
        # of this system: its averaged modes and Liouville sum hold here too
        same = self.same = start if same_system else coarse
        if modes is None and same is not None:
            modes = same.modes
        self.avg = modes if modes is not None else averaged_modes(system)
        self.hill = LatticeHill(system, self.H)
        self.pencil = BalancedPencil(self.hill, self.avg.sq, self.avg.sv)
        self.centre = lattice.position(0)
        self.shell = lattice.shell.astype(float)
        self.boundary = lattice.boundary
        self.lam0 = self.avg.lam
        self.scale0 = np.maximum(np.abs(self.lam0), self.w)
        self.size = 2 * self.n * self.nh
        self.pool: list[Candidate] = []
        self.shifts: list[complex] = []
        self.lu_seconds = self.arnoldi_seconds = 0.0
        self.rng = np.random.default_rng(12345)
        self.matched: dict[int, tuple[list[int], complex]] = {}
        self.tracked: list[int] = []
        self.short: list[complex] = []
        self.warm_starts: list[int] = []
        self.done: dict[int, int] = {}  # clusters whose search met its quota: their quotas
        self.plan()

    # ------------------------------------------------------------------ the clusters
    def quota(self, cid: int) -> int:
        """The exponents of a cluster: one per real averaged exponent, two per complex one."""
        lam0, scale0 = self.lam0, self.scale0
        return sum(1 if abs(lam0[c].imag) <= 1e-9 * scale0[c] else 2 for c in self.clusters[cid])

    def plan(self) -> None:
        """The clusters, their quotas and families; the clusters whose Gershgorin discs lie
        left of the axis need no search (every exponent lies in the union of the discs)."""
        lam0 = self.lam0
        self.clusters = clusters(lam0, targets(lam0, self.w, self.near), self.w)
        self.quotas = {i: self.quota(i) for i in range(len(self.clusters))}
        self.family_of = np.full(lam0.size, -1, dtype=int)
        for i, cl in enumerate(self.clusters):
            self.family_of[cl] = i
        for m in np.flatnonzero(self.family_of < 0):  # the conjugates stand for their targets
            self.family_of[m] = self.family_of[int(np.argmin(np.abs(lam0 - np.conj(lam0[m]))))]
        self.discs = np.zeros(lam0.size)
        self.skipped: list[int] = []
        if self.near is None and lam0.size:
            upper_modes = [int(m) for cl in self.clusters for m in cl]
            self.discs[upper_modes] = self.avg.gershgorin(self.system, upper_modes)
            for cid, cl in enumerate(self.clusters):
                reach = lam0[cl].real + self.discs[cl]
                if np.all(reach < -1e-6 * np.maximum(np.abs(lam0[cl]), self.w)):
                    self.skipped.append(cid)
                    self.quotas[cid] = 0
        self.check_room(planned=len(self.clusters) - len(self.skipped))

    # ------------------------------------------------------------------ memory
    def check_room(self, planned: int | None = None, done: int = 0) -> None:
        """Refuse the search (:class:`~rheolin.budget.MemoryBudgetError`) when it does not
        fit its ``room``: the estimate for ``planned`` clusters before it starts, else the
        operator's estimate and the eigenvectors held after ``done`` clusters."""
        if self.room is None:
            return
        from ..budget import MemoryBudgetError, format_bytes
        from .footprint import lattice_memory

        what = (
            f"the lattice search (order {self.lattice.order}, {self.nh} harmonics, size "
            f"{self.size})"
        )
        if planned is not None:
            need = lattice_memory(self.system, self.lattice, clusters=planned)
            told = f"needs an estimated {format_bytes(need)} for the {planned} clusters it searches"
        else:
            if self._base is None:  # the operator, its factor and the Arnoldi basis
                self._base = lattice_memory(self.system, self.lattice, clusters=0)
            held = sum(int(c.y.nbytes) for c in self.pool)
            need = self._base + held
            told = (
                f"holds {format_bytes(held)} of eigenvectors after {done} clusters, "
                f"{format_bytes(need)} with its operator's estimate"
            )
        if need > self.room:
            raise MemoryBudgetError(
                f"{what} {told}, more than the {format_bytes(self.room)} the memory budget "
                "leaves it; lower the lattice order or condense the model, or raise the "
                "budget (RHEOLIN_MEMORY_BUDGET or `memory_budget`)"
            )

    # ------------------------------------------------------------------ candidates
    def candidate(self, yb: np.ndarray, lam: complex, shift: int) -> Candidate:
        """A Ritz pair (or tracked pair) with its energy per harmonic, the averaged modes it
        carries and the clusters it may stand for."""
        n, nh, H, avg = self.n, self.nh, self.H, self.avg
        e = harmonic_energy(yb, n, nh)
        tot = e.sum()
        e = e / tot if tot > 0 else e
        top = np.argsort(-e, kind="stable")[:2]
        mw = np.abs(avg.WB @ harmonic_block(yb, self.centre, n, nh))
        dom = int(np.argmax(mw))
        # rounding scatter: that of the averaged mode carrying the most energetic harmonic
        mt = np.abs(avg.WB @ harmonic_block(yb, int(top[0]), n, nh))
        at_top = int(np.argmax(mt))
        # the clusters it may stand for: modes carrying its energy at 0 or at its top harmonic
        share = np.maximum(mw / max(mw.max(), 1e-300), mt / max(mt.max(), 1e-300))
        fam: list[int] = []
        for m in np.argsort(-share, kind="stable"):
            if share[m] < ACCEPT_WEIGHT:
                break
            f = int(self.family_of[m])
            if f >= 0 and f not in fam:
                fam.append(f)
        return Candidate(
            complex(lam),
            yb,
            e,
            float(self.shell @ e),
            float(e[self.boundary].sum()),
            (int(H[top[0]]), int(H[top[-1]])),
            dom,
            shift,
            mw / mw[dom] if mw[dom] > 0 else mw,
            SAFETY * float(avg.bound[at_top]),
            tuple(fam),
        )

    def share(self, c: Candidate, cid: int) -> float:
        """Energy fraction of the cluster's modes (and their conjugates) over all harmonics."""
        n, nh = self.n, self.nh
        blocks = np.concatenate(
            [c.y[: n * nh].reshape(nh, n), c.y[n * nh :].reshape(nh, n)], axis=1
        )
        modal = np.abs(blocks @ self.avg.WB.T) ** 2
        mine = np.flatnonzero(self.family_of == cid)
        total = modal.sum()
        return float(modal[:, mine].sum() / total) if total > 0 else 0.0

    # ------------------------------------------------------------------ one cluster
    def previous(self, cid: int) -> tuple[list[int], complex]:
        """The previous speed's rows standing for the cluster, and its move since."""
        if cid not in self.matched:
            start = self.start
            self.matched[cid] = (
                previous_rows(start, self.lam0, self.clusters[cid], self.w)
                if start is not None and not self.same_system
                else ([], 0j)
            )
        return self.matched[cid]

    def find(self, cid: int) -> list[Candidate]:
        """The cluster's candidates: tracked from the previous speed, else searched."""
        got = self.track_cluster(cid)
        return got if got is not None else self.search_cluster(cid)

    def search_cluster(self, cid: int) -> list[Candidate]:
        """Exponents of one cluster of (nearly) equal averaged exponents, centred copies."""
        n, nh, w, H, rng = self.n, self.nh, self.w, self.H, self.rng
        cluster = self.clusters[cid]
        sigma = complex(np.mean(self.lam0[cluster]))
        rows = None if self.same_system else self.previous(cid)
        resolved = self.coarse is not None
        warm, at = warm_start(self.start, H, n, sigma, w, rng, resolved=resolved, rows=rows)
        continued = warm is not None and not self.same_system  # the previous speed's vectors
        if warm is None and not self.same_system:
            warm, at = warm_start(self.coarse, H, n, sigma, w, rng)
        # a coarser lattice's vectors (a confirmation) converge slower; a cold start slowest
        steps = WARM_STEPS if continued else CONFIRM_STEPS if warm is not None else ARNOLDI_STEPS
        if warm is not None:
            sigma = at  # where the coarse exponents are: their continuations converge first
            self.warm_starts.append(cid)
        t1 = time.perf_counter()
        lu = factor(self.hill, sigma, w, many=not continued)  # a long run on this factor
        sigma = lu.sigma
        self.lu_seconds += time.perf_counter() - t1
        apply = ShiftInvert(self.pencil, lu)
        size = self.size
        v0 = np.zeros(size, dtype=complex)
        mix = rng.standard_normal(cluster.size) + 1j * rng.standard_normal(cluster.size)
        c0 = self.centre
        v0[c0 * n : (c0 + 1) * n] = self.avg.X[:n, cluster] @ mix
        v0[n * nh + c0 * n : n * nh + (c0 + 1) * n] = self.avg.X[n:, cluster] @ mix
        if warm is not None:
            v0 = warm.sum(axis=1) + 1e-2 * v0 / np.linalg.norm(v0)
        # a little of everything: an exact eigenvector would end the Krylov space at once
        v0 += 1e-3 * (rng.standard_normal(size) + 1j * rng.standard_normal(size)) / np.sqrt(size)
        t2 = time.perf_counter()
        self.shifts.append(sigma)
        run = _Run(cid, self.quotas[cid], sigma, len(self.shifts) - 1, warm)
        if warm is not None:
            run.warm_unit = warm / np.linalg.norm(warm, axis=0)
        arnoldi(apply, v0, partial(self.checkpoint, run), steps=steps, tol=ARNOLDI_TOL)
        self.arnoldi_seconds += time.perf_counter() - t2
        for c in run.found:
            c.search = cid
            # a column of the checkpoint's Ritz vectors: copied, or it keeps all of them
            c.y = np.ascontiguousarray(c.y)
        if run.satisfied:
            self.done[cid] = run.need
        else:
            self.short.append(sigma)
        return run.found

    def checkpoint(self, run: _Run, theta: np.ndarray, vecs: np.ndarray) -> bool:
        """Whether a cluster's Arnoldi run may stop at a checkpoint with these converged Ritz
        pairs (which become its candidates)."""
        cid, done, pool = run.cid, self.done, self.pool
        run.found.clear()
        lam = run.sigma + 1.0 / theta
        for i in range(theta.size):
            run.found.append(self.candidate(vecs[:, i], lam[i], run.shift))
        mine = [c for c in run.found if c.centroid <= CENTRED and cid in c.families]
        # the quota is judged jointly with the clusters already searched that these
        # candidates can also stand for: two close modes (x and y on anisotropic
        # bearings) must not both be satisfied by the one exponent nearest them, or a
        # parametric exponent between them (a principal resonance) is never sought
        joint = {f for c in mine for f in c.families if f in done} - {cid}
        quota = {cid: run.need, **{f: done[f] for f in joint}}
        cands = mine + [c for c in pool if c.centroid <= CENTRED and joint.intersection(c.families)]
        run.satisfied = count(select(cands, quota, self.w, self.nh)) >= sum(quota.values())
        if not run.satisfied and run.warm is None:
            # a cold search whose cluster's exponents are all converged but none is
            # centred (energy out at the lattice edge: unresolved, settled on a finer
            # lattice) ends when the best-centred copy stops improving: more steps find
            # copies further from the shift, not a better one
            ours = [c.centroid for c in run.found if cid in c.families]
            best = min(ours, default=np.inf)
            run.checkpoints += 1
            stalled = (
                run.checkpoints >= STALL_CHECKPOINT
                and len(ours) >= run.need
                and best >= (1.0 - STALL_GAIN) * run.best
            )
            run.best = min(run.best, best)
            return stalled
        if not run.satisfied and run.warm_unit is not None:
            # a warm start ends when each coarse eigenvector has its continuation: a
            # converged Ritz vector close to it (a mixed cluster's quota may never be
            # met by centred copies)
            # normalized after the product: no copy of the Ritz vectors
            overlap = np.abs(run.warm_unit.conj().T @ vecs) / np.linalg.norm(vecs, axis=0)
            overlap = overlap.max(axis=1)
            return bool(np.all(overlap >= WARM_OVERLAP))
        return run.satisfied

    def track_cluster(self, cid: int) -> list[Candidate] | None:
        """The cluster's exponents continued from the previous speed's (None: not possible
        or not accepted; the cluster is then searched)."""
        start, lam0, w, pencil = self.start, self.lam0, self.w, self.pencil
        if start is None or self.same_system or not np.array_equal(start.indices, self.H):
            return None
        mine, moved = self.previous(cid)
        # only representatives standing for this cluster alone (as its search's would be): a
        # mixed one is searched again
        if not mine or any(len(start.related[i]) != 1 for i in mine):
            return None
        # a Newton step may go a quarter of the way to the nearest other averaged exponent
        others = np.ones(lam0.size, dtype=bool)
        others[self.clusters[cid]] = False
        sigma = complex(np.mean(lam0[self.clusters[cid]]))
        reach = 0.25 * float(np.min(np.abs(lam0[others] - sigma), initial=np.inf))
        found: list[Candidate] = []
        for i in mine:
            vec = start.vectors[i]
            assert vec is not None
            q1, _ = pencil.unbalanced(vec)
            # the exponent moves with its averaged one: by the rate seen last time (the
            # secant dlambda / dsigma of the previous step), else one to one
            rate = start.rate[i] if start.rate.size == start.exponents.size else np.nan
            rate = complex(rate) if np.isfinite(rate) else 1.0
            lam_t = complex(start.exponents[i] + rate * moved)
            for _ in range(TRACK_POLISH):
                lam_t, q1, u, yq = polish(self.hill, lam_t, q1, w, step=reach)
                xb = pencil.first_order(q1, lam_t)
                res = pencil.residual(q1, lam_t)
                scale = (pencil.normA + abs(lam_t) * pencil.normB) * float(np.linalg.norm(xb))
                if not np.isfinite(lam_t) or res <= TRACK_TOL * scale:
                    break
            if not (np.isfinite(lam_t) and res <= TRACK_TOL * scale):
                return None
            c = self.candidate(xb, lam_t, -1)
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
        if count(select(found, {cid: self.quotas[cid]}, w, self.nh)) < self.quotas[cid]:
            return None
        self.tracked.append(cid)
        self.done[cid] = self.quotas[cid]
        return found

    # ------------------------------------------------------------------ the whole search
    def search_certified(self) -> None:
        """A certified cluster may still hold the leading exponent (its disc reaches right
        of every computed one): those are searched too, rightmost disc first, so that the
        largest real part reported is an exponent's, not the best of the rest."""
        right = {
            cid: float(np.max(self.lam0[self.clusters[cid]].real + self.discs[self.clusters[cid]]))
            for cid in self.skipped
        }
        for cid in sorted(self.skipped, key=lambda c: -right[c]):
            lead = max((c.lam.real for c in self.pool), default=-np.inf)
            if right[cid] <= lead:
                break
            self.skipped.remove(cid)
            self.quotas[cid] = self.quota(cid)
            self.pool.extend(self.find(cid))
            self.check_room(done=len(self.shifts) + len(self.tracked))

    def info(self) -> dict[str, Any]:
        """What the search did (``seconds`` so far)."""
        skipped, lam0, discs = self.skipped, self.lam0, self.discs
        return {
            "lattice_size": self.nh,
            "lattice_order": self.lattice.order,
            "hill_size": self.size,
            "shifts": len(self.shifts),
            "lu_seconds": self.lu_seconds,
            "arnoldi_seconds": self.arnoldi_seconds,
            "seconds": time.perf_counter() - self.t0,
            "short_searches": [complex(x) for x in self.short],
            "warm_starts": len(self.warm_starts),
            "tracked": len(self.tracked),
            "certified_modes": np.concatenate(
                [lam0[self.clusters[c]] for c in skipped] + [np.zeros(0, complex)]
            ),
            "certified_radii": np.concatenate(
                [discs[self.clusters[c]] for c in skipped] + [np.zeros(0)]
            ),
        }

    def liouville(self) -> tuple[float, float]:
        """Liouville's sum of the real parts and its uncertainty; none for a band (it sums
        every exponent, and the band's are not all of them)."""
        if getattr(self.avg, "partial", False):
            return float("nan"), float("inf")
        same = self.same
        return same.liouville if same is not None else liouville_sum(self.system)

    def run(self) -> LatticeExponents:
        """Every cluster tracked or searched, the certified ones that may lead searched too,
        one representative per exponent selected and turned into the result."""
        for cid in range(len(self.clusters)):
            if cid not in self.skipped:
                self.pool.extend(self.find(cid))
                self.check_room(done=len(self.shifts) + len(self.tracked))
        self.search_certified()
        expected = int(sum(self.quotas.values()))
        reps = select(self.pool, self.quotas, self.w, self.nh, share=self.share)
        self.pool = []  # the representatives keep theirs; the other candidates' vectors go
        out = lattice_result(
            self.pencil,
            self.system,
            self.lattice,
            self.avg,
            reps,
            self.clusters,
            self.family_of,
            self.discs,
            expected=expected,
            liouville=self.liouville(),
            info=self.info(),
            defer_truncation=self.defer_truncation,
        )
        out.info["seconds"] = time.perf_counter() - self.t0  # the representatives included
        return out
