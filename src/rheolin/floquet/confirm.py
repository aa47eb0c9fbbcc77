"""Settling unresolved exponents on a finer lattice, near them only."""

from __future__ import annotations

import copy

import numpy as np

from ..budget import MemoryBudgetError
from ..harmonics.lattice import Lattice, harmonic_lattice
from ..system.periodic import PeriodicSystem
from .checks import agree, certify, split_gaps
from .outcome import LatticeExponents
from .result import TRUNCATION_SAFETY
from .search import lattice_exponents
from .select import CLUSTER_TOL

__all__ = [
    "cluster_members",
    "confirm_unresolved",
    "lattice_order",
    "open_centres",
    "open_rows",
    "short_rows",
    "snapshot",
    "standard_lattices",
]


def confirm_unresolved(
    system: PeriodicSystem,
    out: LatticeExponents,
    finer: Lattice,
    previous: LatticeExponents | None = None,
    todo: np.ndarray | None = None,
    start: LatticeExponents | None = None,
    room: int | None = None,
) -> tuple[LatticeExponents, LatticeExponents | None]:
    """Settle the unresolved, uncertified representatives and the clusters short of their
    exponents (:func:`open_rows`; or the rows ``todo``) on a finer lattice.

    Their clusters are searched again on ``finer`` (only near them), each from its coarse
    eigenvectors, shifted to its coarse exponents: the continuation converges in a few
    Arnoldi steps (a cold search of a strongly mixed cluster runs to the last checkpoint
    without meeting its quota). Where the finer lattice
    resolves a cluster, its exponents replace the coarse ones (each exponent keeps its own
    ``order``; a short cluster's when the finer lattice finds all of them, never more
    exponents than the averaged system has); where it does not either, the cluster is
    confirmed when its largest real
    part is negative at both orders and changes by less than ``1 / TRUNCATION_SAFETY`` of
    its size (the verdict does not move with the truncation). Records
    ``info["confirmed"]``.

    ``previous``: the finer lattice's search at the previous speed of a sweep
    (:class:`~rheolin.floquet.Continuation`); the clusters it covers start from its
    eigenvectors (a few Arnoldi steps), the others from the coarse ones. Returns ``out`` and
    the finer search (None: nothing to settle), which the next speed can start from.

    ``start``: the search whose eigenvectors the clusters start from (default ``out``; a
    confirmation made again from the coarse search after another finer lattice, whose
    eigenvectors ``out`` no longer holds).

    ``room``: the memory [bytes] the finer search may use (:func:`~rheolin.floquet.search.
    lattice_exponents`; its refusal, a :class:`~rheolin.budget.MemoryBudgetError`, leaves
    ``out`` as it was).

    ``todo``: a mask of rows to search again instead (:func:`~rheolin.floquet.accuracy.
    refine_leading`: the leading exponent's cluster, resolved, for its accuracy).

    A search started from the previous speed that leaves a cluster unresolved or short (its
    eigenvectors led Arnoldi to the copies of the previous speed, not to this speed's
    mixed pair: the gear variant inside its principal resonance) is made again from this
    speed's coarse eigenvectors, as without a ``previous``, and that outcome is kept when it
    settles every cluster (``info["confirmed"]["retried"]``; otherwise the continued one,
    which the next speed starts from).
    """
    if previous is None or todo is not None:
        return _confirm(system, out, finer, previous, todo, start, room)
    before = snapshot(out)
    got, fine = _confirm(system, out, finer, previous, None, start, room)
    left = _open(got)
    if left == (0, 0):
        return got, fine
    try:
        again, fine_again = _confirm(system, before, finer, None, None, start, room)
    except MemoryBudgetError:  # the retry does not fit: the continued outcome stands
        got.info["confirmed"]["retried"] = False
        return got, fine
    if _open(again) == (0, 0):
        again.info["confirmed"]["retried"] = True
        return again, fine_again
    got.info["confirmed"]["retried"] = False
    return got, fine


def standard_lattices(lattice: Lattice) -> list[Lattice]:
    """The finer lattices open rows are confirmed on, in turn: the orders ``p + 1`` and
    ``p + 2`` of ``lattice``'s steps (those past a million harmonics left out)."""
    return [x for x in (lattice_order(lattice, lattice.order + k) for k in (1, 2)) if x is not None]


def lattice_order(
    lattice: Lattice, order: int, costs: dict[int, int] | None = None
) -> Lattice | None:
    """The lattice of ``order`` with the same steps, or these ``costs`` (None past a million
    harmonics)."""
    steps = dict(zip(lattice.generators, lattice.costs, strict=True)) if costs is None else costs
    if not steps:
        return None
    try:
        return harmonic_lattice(steps, order, max_size=10**6)
    except ValueError:
        return None


def short_rows(out: LatticeExponents, w: float) -> np.ndarray:
    """The rows of the clusters with fewer exponents than their averaged modes, when the
    search is short of exponents (``complete`` False): inside a parametric resonance the
    search continued from the previous speed can keep the decaying exponent of a locked
    pair and miss the growing one, whose cluster is searched again on a finer lattice."""
    mask = np.zeros(out.exponents.size, dtype=bool)
    if out.complete:
        return mask
    for z in np.unique(out.centre[np.isfinite(out.centre)]):
        rows = cluster_members(out.centre, z, w)
        if rows.sum() < _quota(out, z, w):
            mask |= rows
    return mask


def open_centres(out: LatticeExponents, w: float, todo: np.ndarray | None = None) -> np.ndarray:
    """The centres of the clusters a confirmation searches: those of the rows ``todo``
    (default :func:`open_rows`) in the upper half plane, with the clusters they may also
    stand for."""
    if todo is None:
        todo = open_rows(out, w)
    # upper half plane, real centres included (their imaginary parts are rounding, of
    # either sign)
    upper = out.centre.imag >= -1e-9 * np.maximum(np.abs(out.centre), w)
    # with the clusters they may also stand for (their energy on those modes): two close
    # clusters share their quota in the search, or the stable exponent nearest both satisfies
    # the one searched alone and a parametric exponent between them is lost (the example
    # rotor inside its band at order 1 -> 2 was once decided stable so)
    linked = [z for i in np.flatnonzero(todo) for z in out.related[i]]
    centres = np.unique(np.concatenate([out.centre[todo & upper], np.asarray(linked, complex)]))
    return centres[np.isfinite(centres)]


def open_rows(out: LatticeExponents, w: float) -> np.ndarray:
    """The rows a finer lattice is to settle: unresolved and uncertified, or of a cluster
    short of its exponents (:func:`short_rows`)."""
    return (out.unresolved & ~out.certified) | short_rows(out, w)


def cluster_members(arr: np.ndarray, z: complex, w: float) -> np.ndarray:
    """The entries of ``arr`` in the cluster centred at ``z`` or at its conjugate."""
    tol = CLUSTER_TOL * max(abs(z), w)
    return np.asarray((np.abs(arr - z) <= tol) | (np.abs(arr - np.conj(z)) <= tol))


def _quota(out: LatticeExponents, z: complex, w: float) -> int:
    """The exponents of the cluster centred at ``z``, conjugates included: one per averaged
    exponent in it or in its conjugate cluster."""
    return int(cluster_members(out.averaged, z, w).sum())


def _open(out: LatticeExponents) -> tuple[int, int]:
    """What is left open: exponents missing (no finer lattice looks for them again), then
    unresolved, uncertified ones (a finer lattice may settle them)."""
    missing = max(out.expected - out.exponents.size, 0)
    return missing, int(np.sum(out.unresolved & ~out.certified))


def snapshot(out: LatticeExponents) -> LatticeExponents:
    """A copy of ``out`` that a confirmation does not change (it replaces the arrays, and
    marks ``certified`` and ``uncertainty`` in place)."""
    kept = copy.copy(out)
    kept.info = dict(out.info)
    kept.certified = out.certified.copy()
    kept.uncertainty = out.uncertainty.copy()
    return kept


def _confirm(
    system: PeriodicSystem,
    out: LatticeExponents,
    finer: Lattice,
    previous: LatticeExponents | None,
    todo: np.ndarray | None,
    start: LatticeExponents | None = None,
    room: int | None = None,
) -> tuple[LatticeExponents, LatticeExponents | None]:
    """:func:`confirm_unresolved` from one start (``out`` unchanged when the finer search
    is refused by its ``room``)."""
    coarse = out if start is None else start
    w = system.omega
    if todo is None:
        todo = open_rows(out, w)
    if not todo.any():
        out.info["confirmed"] = {"order": finer.order, "clusters": 0, "replaced": 0, "confirmed": 0}
        return out, None
    centres = open_centres(out, w, todo)
    if centres.size == 0:
        out.info["confirmed"] = {"order": finer.order, "clusters": 0, "replaced": 0, "confirmed": 0}
        return out, None
    fine = lattice_exponents(
        system,
        finer,
        near=centres,
        start=coarse if previous is None else previous,
        same_system=previous is None,
        coarse=None if previous is None else coarse,
        defer_truncation=True,
        room=room,
    )
    fields = (
        "exponents", "bounds", "truncation", "edge", "centroid", "dominant", "certified",
        "centre", "unresolved", "order", "uncertainty", "radius", "rate",
    )  # fmt: skip
    keep = np.ones(out.exponents.size, dtype=bool)
    take = np.zeros(fine.exponents.size, dtype=bool)
    replaced = confirmed = 0

    def members(arr: np.ndarray, z: complex) -> np.ndarray:
        return cluster_members(arr, z, w)

    def replaces(mine: np.ndarray, there: np.ndarray, zs: np.ndarray) -> bool:
        # resolved, and as many as the coarse rows, or exactly the clusters' quotas (a coarse
        # cluster short of an exponent, or holding a copy counted as another one) without
        # more exponents in all than the averaged system has
        if not there.any() or fine.unresolved[there].any():
            return False
        got, had = int(there.sum()), int(mine.sum())
        if got == had:
            return True
        zs = np.unique(np.where(zs.imag < 0, np.conj(zs), zs))
        if got != sum(_quota(out, z, w) for z in zs):
            return False
        total = int(keep.sum() - (keep & mine).sum() + take.sum() + (there & ~take).sum())
        return got < had or total <= out.expected

    every = np.any([members(out.centre, z) for z in centres], axis=0)
    there_all = np.any([members(fine.centre, z) for z in centres], axis=0)
    if replaces(every, there_all, centres):
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
        if replaces(mine, there, np.array([z])):
            keep &= ~mine
            take |= there
            replaced += 1
        elif agree(out.exponents[mine], fine.exponents[there], fine.unresolved[there]):
            certify(out, mine, out.exponents[mine], fine.exponents[there])
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
    if fine.settle is not None:  # the truncation estimates of the exponents taken
        fine.settle(fine, np.flatnonzero(take))
        fine.settle = None  # it holds the finer lattice's operators (and factors)
    for name in fields:
        setattr(out, name, np.concatenate([getattr(out, name)[keep], getattr(fine, name)[take]]))
    out.partner = [p for p, k in zip(out.partner, keep, strict=True) if k] + [
        p for p, t in zip(fine.partner, take, strict=True) if t
    ]
    out.related = [r for r, k in zip(out.related, keep, strict=True) if k] + [
        r for r, t in zip(fine.related, take, strict=True) if t
    ]
    # the coarse vectors do not live on the finer lattice: a later refinement starts afresh
    # from these (the kept ones are dropped)
    kept: list[np.ndarray | None] = [None] * int(keep.sum())
    out.vectors = kept + [v for v, t in zip(fine.vectors, take, strict=True) if t]
    out.indices = fine.indices
    out.lattice = finer
    out.split_gap = split_gaps(out.exponents, finer.indices, system.omega)
    out.info["confirmed"] = {
        "order": finer.order,
        "clusters": int(centres.size),
        "replaced": replaced,
        "confirmed": confirmed,
        "warm_starts": int(fine.info.get("warm_starts", 0)),
        "tracked": int(fine.info.get("tracked", 0)),
    }
    return out, fine
