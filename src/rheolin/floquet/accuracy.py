"""Accuracy on demand: the largest real part refined to a relative tolerance.

A verdict needs each exponent only on the right side of the axis; the largest real part (the
growth rate variants are compared by) comes with the uncertainty of its lattice,
``TRUNCATION_SAFETY`` times its truncation estimate: about 1e-3 relative near a resonance on
an order-1 lattice. :func:`refine_leading` searches the leading exponent's cluster again on
finer lattices, near it only (:func:`~rheolin.floquet.confirm.confirm_unresolved` with its
rows), until its stated uncertainty meets ``rtol |max_real|``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..budget import MemoryBudgetError
from ..budget import memory_budget as resolve_budget
from ..harmonics.lattice import Lattice
from ..system.periodic import PeriodicSystem
from .confirm import (
    cluster_members,
    confirm_unresolved,
    lattice_order,
    open_centres,
    snapshot,
)
from .footprint import lattice_memory
from .grown import FAR, grown_open
from .outcome import LatticeExponents
from .result import SAFETY

__all__ = [
    "DEFAULT_RTOL",
    "OPEN_ORDERS",
    "RTOL_ORDERS",
    "ZETA_FLOOR",
    "leading_uncertainty",
    "refine_leading",
    "refine_open",
    "target",
]

#: Relative accuracy of the largest real part that :func:`rheolin.floquet` meets by default.
DEFAULT_RTOL = 1e-4

#: At most this many refinement steps (lattice orders) per verdict.
RTOL_ORDERS = 3

#: Orders above their own at which :func:`refine_open` searches the exponents that keep a
#: verdict open, near them only.
OPEN_ORDERS = 2

#: A real part near zero has no relative accuracy: the target is ``rtol`` times the larger
#: of ``|Re|`` and this damping ratio times ``|lambda|`` (0.1 %).
ZETA_FLOOR = 1e-3


def target(rtol: float, lam: complex) -> float:
    """The uncertainty that meets ``rtol`` for the exponent ``lam``.

    >>> target(1e-4, -5.0 + 1000j), target(1e-4, 0.01 + 1000j)
    (0.0005, 0.0001)
    """
    return float(rtol * max(abs(lam.real), ZETA_FLOOR * abs(lam)))


def leading_uncertainty(out: LatticeExponents, row: int) -> float:
    """The stated uncertainty of row ``row``'s real part: its truncation uncertainty
    (``TRUNCATION_SAFETY`` times the estimate, or its disc), at least its tolerance."""
    return float(max(out.uncertainty[row], SAFETY * out.bounds[row]))


def refine_leading(
    system: PeriodicSystem,
    out: LatticeExponents,
    lattice: Lattice,
    rtol: float,
    budget: Any = None,
    continuation: Any = None,
) -> tuple[LatticeExponents, dict[str, Any]]:
    """Refine the leading exponent of ``out`` (the verdict's search on ``lattice``, its
    confirmations made and truncation estimates settled) until its uncertainty meets
    :func:`target` (``rtol`` times its real part; ``inf``: nothing is refined); returns
    ``out`` and what was done (``info["accuracy"]``).

    Each step searches the leading cluster (with the clusters it also stands for) again on
    the lattice one order up, near it only, starting one order above the leading exponent's
    own; where that lattice resolves the cluster with a smaller uncertainty, its exponents
    replace the coarse ones (with their own truncation estimates). It stops when the
    uncertainty is met, after :data:`RTOL_ORDERS` steps, when the next lattice would exceed
    the memory budget, or when the leading exponent is judged by a Gershgorin disc or not
    resolved (no finer search makes those more accurate). ``continuation`` (over a sweep):
    each step starts from the previous speed's search on the same lattice, and is kept for
    the next.
    """
    info: dict[str, Any] = {"rtol": float(rtol), "orders": [], "met": False, "memory": 0}
    if not np.isfinite(rtol):
        info["met"] = True
        return out, info
    limit = resolve_budget(budget)
    order = lattice.order
    n = system.n
    for _ in range(RTOL_ORDERS + 1):
        if out.exponents.size == 0:
            break
        i = int(np.argmax(out.exponents.real))
        unc = leading_uncertainty(out, i)
        if unc <= target(rtol, complex(out.exponents[i])):
            info["met"] = True
            break
        if len(info["orders"]) >= RTOL_ORDERS or out.unresolved[i] or out.certified[i]:
            break
        todo = _cluster_rows(out, i, system.omega)
        order = max(order, int(out.order[i])) + 1
        finer = lattice_order(lattice, order)
        clusters = int(open_centres(out, system.omega, todo).size)
        need = lattice_memory(system, finer, clusters=clusters) if finer is not None else 0
        if finer is None or need > limit:
            break
        previous = continuation.start(n, finer) if continuation is not None else None
        before = snapshot(out)
        steps = out.info.get("confirmed")  # the verdict's confirmations, kept in its info
        try:
            out, fine = confirm_unresolved(system, out, finer, previous, todo=todo, room=limit)
        except MemoryBudgetError as exc:  # more eigenvectors than estimated: out stands
            info["refused"] = str(exc)
            break
        _restore(out, steps)
        info["orders"].append(order)
        info["memory"] = max(info["memory"], need)
        if continuation is not None and fine is not None:
            continuation.keep(n, finer, fine)
        j = int(np.argmax(out.exponents.real))
        if leading_uncertainty(out, j) >= unc:  # not better: keep the coarse exponents
            out = before
    return out, info


def refine_open(
    system: PeriodicSystem,
    out: LatticeExponents,
    lattice: Lattice,
    judge: Callable[[LatticeExponents], Any],
    budget: Any = None,
    continuation: Any = None,
    finest: int | None = None,
) -> tuple[LatticeExponents, list[int], int]:
    """Decide a verdict that only the truncation estimates of some exponents keep open.

    ``judge(out)`` is the :class:`~rheolin.floquet.FloquetResult` of ``out`` (the verdict's
    search on ``lattice``, confirmations made and truncation estimates settled); its
    :meth:`~rheolin.floquet.FloquetResult.truncation_open` exponents (resolved, within ten
    truncation estimates of the axis) have their clusters searched again on the lattice one
    order above their own, near them only, up to :data:`OPEN_ORDERS` orders up, to the
    order ``finest`` at most (None: no limit; an exponent already there is left as it is)
    and within the memory budget. Where that
    lattice resolves a cluster with its full quota, its exponents replace the coarse ones
    with their own truncation estimates, and the verdict is judged by the same rules
    (agreement between orders certifies unresolved exponents only, never these). The rest
    of the lattice is not searched again: its exponents are decided by their own estimates.
    ``continuation`` (over a sweep): each search starts from the previous speed's on its
    lattice, and is kept for the next speed when the verdict is decided. Returns ``out``,
    the orders searched and the largest memory estimate among them.

    Each step first grows, for the open exponents whose eigenvectors it holds on the lattice
    they were resolved on, all far left of the leading exponent
    (:data:`~rheolin.floquet.grown.FAR`), that lattice one step along their leaks
    (:func:`~rheolin.floquet.grown.grown_open`) when it is smaller than the standard order
    they would be searched on, and searches their clusters on it; its outcome is kept when
    it decides the verdict or brings those clusters' exponents nearer the axis by their
    uncertainty (``Re`` plus uncertainty smaller), and the next step grows from it;
    otherwise it is dropped and those exponents take the standard order as without it
    (``info["refined_grown"]`` records each such search).
    """
    orders: list[int] = []
    searches: list[tuple[Lattice, LatticeExponents]] = []
    used = 0
    limit = resolve_budget(budget)
    n, w = system.n, system.omega
    last: tuple[Lattice, LatticeExponents] | None = None  # the grown search kept last
    growing = True
    for step in range(OPEN_ORDERS + 1):
        verdict = judge(out)
        rows = _open_now(out, verdict)
        if verdict.decided and continuation is not None:
            # kept only when they decide: else the whole lattice is searched at the next
            # order, better started from the previous speed's search of all of it
            for kept_lattice, kept in searches:
                continuation.keep(n, kept_lattice, kept)
        if verdict.decided or rows.size == 0 or step == OPEN_ORDERS:
            break
        grew = np.zeros(0, dtype=complex)  # the centres of the clusters grown this step
        if growing:
            out, grew, grown_step = _grow_open(
                system, out, rows, lattice, judge, limit, finest, last
            )
            if grown_step is not None:
                last = grown_step[0]
                used = max(used, grown_step[1])
            else:
                growing = False
            if grew.size:
                verdict = judge(out)
                if verdict.decided:
                    continue  # the next step records it
                rows = _open_now(out, verdict)
                done = np.any([cluster_members(out.centre[rows], z, w) for z in grew], axis=0)
                rows = rows[~done]
        if finest is not None:
            rows = rows[out.order[rows] < finest]  # those at the top stay as they are
        if rows.size == 0:
            if grew.size:
                continue
            break
        todo = np.any([_cluster_rows(out, int(i), w) for i in rows], axis=0)
        order = max(lattice.order, int(out.order[rows].max())) + 1
        finer = lattice_order(lattice, order) if finest is None or order <= finest else None
        if finer is None:
            if grew.size:
                continue
            break
        estimate = lattice_memory(system, finer, clusters=int(open_centres(out, w, todo).size))
        if estimate > limit:
            if grew.size:
                continue
            break
        used = max(used, estimate)
        previous = continuation.start(n, finer) if continuation is not None else None
        steps = out.info.get("confirmed")
        try:
            out, fine = confirm_unresolved(system, out, finer, previous, todo=todo, room=limit)
        except MemoryBudgetError as exc:  # more eigenvectors than estimated: out stands
            out.info["memory_refused"] = str(exc)
            break
        _restore(out, steps)
        orders.append(order)
        if fine is not None:
            searches.append((finer, fine))
    return out, orders, used


def _open_now(out: LatticeExponents, verdict: Any) -> np.ndarray:
    """The rows of ``out`` whose truncation estimates keep ``verdict`` (its result) open."""
    rank = np.argsort(-out.exponents.real, kind="stable")  # the result's order
    return np.asarray(rank[verdict.truncation_open()], dtype=int)


def _grow_open(
    system: PeriodicSystem,
    out: LatticeExponents,
    rows: np.ndarray,
    lattice: Lattice,
    judge: Callable[[LatticeExponents], Any],
    limit: int,
    finest: int | None,
    last: tuple[Lattice, LatticeExponents] | None,
) -> tuple[LatticeExponents, np.ndarray, tuple[tuple[Lattice, LatticeExponents], int] | None]:
    """One step of :func:`refine_open` on a lattice grown along the leaks of the open rows
    ``rows`` (:func:`~rheolin.floquet.grown.grown_open`): from the grown search kept ``last``
    or else from the eigenvectors ``out`` holds on its lattice. Returns ``out`` (the grown
    search's exponents when kept, else as it was), the centres of the clusters it replaced
    (none when not kept) and, when kept, ``(its lattice and search, its memory estimate)``."""
    w = system.omega
    none = np.zeros(0, dtype=complex)
    src, held = (last[1], last[0]) if last is not None else (out, out.lattice)
    if held is None or not np.array_equal(np.asarray(src.indices), np.asarray(held.indices)):
        return out, none, None
    lead = float(out.exponents.real.max(initial=-np.inf))
    upper = out.centre.imag >= -1e-9 * np.maximum(np.abs(out.centre), w)
    src_upper = src.centre.imag >= -1e-9 * np.maximum(np.abs(src.centre), w)
    centres: list[complex] = []
    mine = np.zeros(src.exponents.size, dtype=bool)  # the vectors the leaks are read from
    for i in rows[upper[rows]]:
        z = complex(out.centre[i])
        there = cluster_members(src.centre, z, w) & src_upper
        if (
            not np.isfinite(z)
            or not there.any()
            or any(src.vectors[j] is None for j in np.flatnonzero(there))
            or not (lead < 0 and out.exponents.real[i] < FAR * lead)
        ):
            continue  # its leaks not known here, or near the axis: the standard order
        centres.append(z)
        mine |= there
    if not centres:
        return out, none, None
    grown = grown_open(src, mine, held)
    if grown is None:
        return out, none, None
    near = np.array(centres)
    todo = np.any([cluster_members(out.centre, z, w) for z in near], axis=0)
    order = max(lattice.order, int(out.order[todo].max())) + 1
    plain = lattice_order(lattice, order) if finest is None or order <= finest else None
    if plain is not None and len(grown) >= len(plain):
        return out, none, None  # nothing saved: the standard order
    estimate = lattice_memory(system, grown, clusters=int(open_centres(out, w, todo).size))
    record: dict[str, Any] = {
        "order": grown.order, "harmonics": len(grown), "clusters": len(centres), "kept": False,
    }  # fmt: skip
    out.info.setdefault("refined_grown", []).append(record)
    if estimate > limit:
        record["refused"] = True
        return out, none, None
    before = snapshot(out)
    reach = _reach(out, near, w)
    steps = out.info.get("confirmed")
    try:
        got, fine = confirm_unresolved(system, out, grown, None, todo=todo, room=limit)
    except MemoryBudgetError:  # more eigenvectors than estimated: as without it
        record["refused"] = True
        return before, none, None
    _restore(got, steps)
    if fine is not None and (judge(got).decided or _reach(got, near, w) < reach):
        record["kept"] = True
        return got, near, ((grown, fine), estimate)
    return before, none, None


def _reach(out: LatticeExponents, centres: np.ndarray, w: float) -> float:
    """How far right the exponents of the clusters at ``centres`` reach by their
    uncertainty: the largest real part plus uncertainty among them."""
    rows = np.any([cluster_members(out.centre, z, w) for z in centres], axis=0)
    return float(np.max(out.exponents.real[rows] + out.uncertainty[rows], initial=-np.inf))


def _restore(out: LatticeExponents, steps: Any) -> None:
    """Put back the verdict's record of its confirmations (``info["confirmed"]``), which a
    refinement's own confirmation overwrites."""
    out.info.pop("confirmed", None)
    if steps is not None:
        out.info["confirmed"] = steps


def _cluster_rows(out: LatticeExponents, row: int, w: float) -> np.ndarray:
    """Rows of ``row``'s cluster (its centre and the conjugate centre)."""
    z = out.centre[row]
    if not np.isfinite(z):
        mask = np.zeros(out.exponents.size, dtype=bool)
        mask[row] = True
        return mask
    tol = 1e-9 * max(abs(z), w)
    return (np.abs(out.centre - z) <= tol) | (np.abs(out.centre - np.conj(z)) <= tol)
