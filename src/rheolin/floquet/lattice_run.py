"""The lattice verdict of ``floquet``: the coarsest lattice first, its unresolved and short
clusters confirmed on finer lattices near them, the order raised while undecided, within the
memory budget."""

from __future__ import annotations

import logging
import time
from typing import Any

import numpy as np

from ..budget import MemoryBudgetError, format_bytes
from ..budget import memory_budget as resolve_budget
from ..harmonics.lattice import Lattice
from ..linalg.threads import single_thread_blas
from ..system.periodic import PeriodicSystem
from . import large
from .accuracy import leading_uncertainty, refine_leading, refine_open
from .band import BandAveraged, band_memory, band_vectors
from .confirm import (
    confirm_unresolved,
    open_centres,
    open_rows,
    snapshot,
    standard_lattices,
)
from .continuation import Continuation
from .footprint import lattice_memory
from .grown import grown_further, grown_lattice
from .resonance import floquet_lattice
from .result import FloquetResult, add_note, floquet_result
from .search import lattice_exponents

__all__ = [
    "DEFAULT_LATTICE_ORDER",
    "MAX_AUTO_ORDER",
    "check_budget",
    "floquet_on_lattice",
    "lattice_auto",
]

log = logging.getLogger(__name__)


#: First lattice order of ``floquet(system)``; raised one order at a time, up to
#: :data:`MAX_AUTO_ORDER`, while the verdict is undecided (and the larger lattice fits the
#: memory budget). Its unresolved exponents are already continued on orders ``p + 1`` and
#: ``p + 2`` near them, so the coarse lattice decides most systems, faster than a finer one
#: and with the same verdict (bench/stability.py, design notes).
DEFAULT_LATTICE_ORDER = 1


#: Highest order ``floquet(system)`` raises the lattice to by itself.
MAX_AUTO_ORDER = 3


def check_budget(estimate: int, budget: Any, what: str, advice: str) -> None:
    """Refuse ``what`` (:class:`~rheolin.budget.MemoryBudgetError`) when its estimated memory
    exceeds the budget, saying ``advice``."""
    limit = resolve_budget(budget)
    if estimate > limit:
        raise MemoryBudgetError(
            f"{what} needs an estimated {format_bytes(estimate)}, more than the memory budget "
            f"of {format_bytes(limit)}; {advice}, or raise the budget (RHEOLIN_MEMORY_BUDGET "
            "or `memory_budget`)"
        )


def lattice_auto(
    system: PeriodicSystem,
    order: int | None,
    budget: Any,
    *,
    refine: bool,
    near: Any = None,
    continuation: Continuation | None = None,
    band: int | None = None,
    rtol: float | None = None,
) -> FloquetResult:
    """Lattice method at ``order`` (default: the coarsest, raised one order at a time up to
    :data:`MAX_AUTO_ORDER` while undecided and the larger lattice fits the budget; where it
    does not, the undecided coarse verdict says so). The lattices see resonances
    (:func:`~rheolin.floquet.resonance.floquet_lattice`). A large model (or ``band``) starts
    from the band of time-averaged modes, built once for every order."""
    with single_thread_blas():  # the averaged modes and lattice costs too
        return _lattice_auto(system, order, budget, refine, near, continuation, band, rtol)


def _lattice_auto(
    system: PeriodicSystem,
    order: int | None,
    budget: Any,
    refine: bool,
    near: Any,
    continuation: Continuation | None,
    band: int | None,
    rtol: float | None,
) -> FloquetResult:
    """:func:`lattice_auto`, BLAS on one thread."""
    t0 = time.perf_counter()  # the whole verdict: a band's modes and scan, every order
    limit = resolve_budget(budget)
    p = DEFAULT_LATTICE_ORDER if order is None else int(order)
    top = max(MAX_AUTO_ORDER, DEFAULT_LATTICE_ORDER)
    modes = None
    if large.uses_band(system, band):
        start = continuation.band_start(system.n) if continuation is not None else None
        modes = large.certified_band(system, band, budget, p, start)
        if continuation is not None:  # the next speed's band starts at this size
            kept = band is None and not large.band_failed(modes)
            continuation.keep_band(system.n, modes.asked if kept else None)
    lat = floquet_lattice(system, p, max_size=10**6, avg=modes)  # one band for both
    res = floquet_on_lattice(
        system, lat, budget=budget, near=near, continuation=continuation, modes=modes,
        rtol=rtol, last=not refine or p >= top,
    )  # fmt: skip
    tried: list[int] = []
    while refine and not res.decided and p < top:
        if res.stable and large.band_failed(modes):
            break  # a finer lattice cannot bound the modes the band leaves out
        finer = floquet_lattice(system, p + 1, max_size=10**6, avg=modes)
        need = search_memory(system, finer, modes)  # what floquet_on_lattice checks
        if need > limit:
            res.info["note"] = (
                f"undecided at lattice order {p}; order {p + 1} ({len(finer)} harmonics) "
                f"would need an estimated {format_bytes(need)}, more than the memory budget "
                f"of {format_bytes(limit)}"
            )
            break
        log.info("floquet: order %d undecided; refining to order %d", p, p + 1)
        try:
            finer_res = floquet_on_lattice(
                system, finer, budget=budget, continuation=continuation, modes=modes,
                rtol=rtol, last=p + 1 >= top,
            )  # fmt: skip
        except MemoryBudgetError as exc:  # found more eigenvectors than estimated
            why = f"undecided at lattice order {p}; order {p + 1} was stopped: {exc}"
            add_note(res.info, why)
            break
        tried.append(p)
        p += 1
        res = finer_res
        res.info["refined_from"] = list(tried)
    res.info["seconds"] = time.perf_counter() - t0
    return res


def search_memory(system: PeriodicSystem, lattice: Lattice, modes: Any = None) -> int:
    """Estimated peak memory [bytes] of the search on ``lattice``, with the band of
    ``modes`` when it is one (:func:`~rheolin.floquet.band.band_memory`)."""
    est = lattice_memory(system, lattice)
    if isinstance(modes, BandAveraged):
        est += band_memory(system, int(modes.lam.size))
    return est


def floquet_on_lattice(
    system: PeriodicSystem,
    lattice: Lattice,
    *,
    budget: Any,
    near: Any = None,
    continuation: Continuation | None = None,
    modes: Any = None,
    rtol: float | None = None,
    last: bool = True,
) -> FloquetResult:
    """The lattice verdict on ``lattice`` (its unresolved exponents confirmed on finer ones);
    with ``rtol``, the leading exponent refined when the verdict is decided or ``last`` (no
    finer order follows)."""
    t0 = time.perf_counter()
    est = search_memory(system, lattice, modes)
    band_held = band_vectors(system, int(modes.lam.size)) if isinstance(modes, BandAveraged) else 0
    limit = resolve_budget(budget)
    kept = 0
    if continuation is not None:  # the previous speed's searches stay until replaced
        if est + continuation.nbytes > limit:
            continuation.clear()  # no room for them: this speed starts cold
        kept = continuation.nbytes
    check_budget(
        est,
        limit,
        f"the lattice Hill problem (order {lattice.order}, {len(lattice)} harmonics, "
        f"size {2 * system.n * len(lattice)})",
        "lower the lattice order",
    )
    with np.errstate(under="ignore"), single_thread_blas():
        start = continuation.start(system.n, lattice) if continuation is not None else None
        # the truncation estimates are made last, for the exponents the confirmations keep
        # (those they replace by finer ones need none)
        out = lattice_exponents(
            system,
            lattice,
            near=near,
            start=start,
            same_system=False,
            defer_truncation=True,
            modes=modes,
            room=max(limit - kept - band_held, 1),  # checked again once its clusters are known
        )
        # what stays alive while finer lattices are searched near open clusters: this
        # lattice's operators, the vectors its result holds, the band's modes and the
        # previous speed's searches; the finer searches get the budget's rest
        held = lattice_memory(system, lattice, searching=False, clusters=0)
        held += out.nbytes + band_held + kept
        room = max(limit - held, 1)
        if continuation is not None and near is None:
            continuation.keep(system.n, lattice, out)
        # unresolved exponents and clusters short of theirs: search those clusters again on
        # finer lattices (p + 1, p + 2), only near them, as long as the memory budget allows;
        # first on the lattice grown along the steps they leak to when they all lie far left
        # (docs/stability.md, section 4)
        steps: list[Any] = []
        used = est + kept  # the largest lattice's estimate: what the verdict needed
        if near is None and np.any(open_rows(out, system.omega)):
            chain = Chain(system, held, room, continuation)
            grown = grown_lattice(out, lattice, system.omega)
            standard = standard_lattices(lattice)
            if grown is not None:
                before = snapshot(out)  # its eigenvectors, which a confirmation drops
                out = chain.run(out, [grown], grown=True)
                if np.any(open_rows(out, system.omega)):
                    # the rows it settled stay; the rest from the coarse eigenvectors
                    out = chain.run(out, standard, start=before, grow=True)
                if np.any(open_rows(out, system.omega)):
                    # still open: every open cluster again, as without the grown lattice
                    # (a cluster searched apart from the others it was open with can miss
                    # the joint settlement)
                    for step in chain.steps:
                        step["kept"] = False
                    out = chain.run(before, standard, grow=True)
            else:
                out = chain.run(out, standard, grow=True)
            steps, used = chain.steps, max(used, chain.used)
            if chain.refused:
                out.info["memory_refused"] = chain.refused
        if steps:
            out.info["confirmed"] = steps
        if out.settle is not None:
            out.settle(out, np.flatnonzero(np.isnan(out.truncation)))
            out.settle = None  # it holds the lattice's operators
        res = search_result(system, out, lattice, near, used, t0, modes)
        if near is None and not res.decided and res.truncation_open().any():
            # exponents whose truncation estimate alone keeps the verdict open: their
            # clusters on finer lattices, near them only, before the whole lattice is (no
            # finer than the top order's confirmations reach)
            out, opened, need = refine_open(
                system, out, lattice,
                lambda o: search_result(system, o, lattice, near, used, t0, modes),
                room, continuation, max(MAX_AUTO_ORDER, lattice.order) + 2,
            )  # fmt: skip
            used = max(used, held + need if need else 0)
            res = search_result(system, out, lattice, near, used, t0, modes)
            res.info["refined_near"] = opened
        if rtol is not None and near is None and (last or res.decided):
            out, accuracy = refine_leading(system, out, lattice, rtol, room, continuation)
            if accuracy["memory"]:  # its finer lattices, beside what this one holds
                used = max(used, held + int(accuracy["memory"]))
            res = search_result(system, out, lattice, near, used, t0, modes)
            res.info["accuracy"] = accuracy
    refused = res.info.pop("memory_refused", None)
    if refused and not res.decided:
        why = f"a confirmation on a finer lattice was stopped: {refused}"
        add_note(res.info, why)
    return res


class Chain:
    """Confirmations on finer lattices in turn, each near the rows still open, within the
    room the memory budget leaves; records each step (``steps``) and the largest memory
    estimate (``used``)."""

    def __init__(
        self, system: PeriodicSystem, held: int, room: int, continuation: Continuation | None
    ) -> None:
        self.system, self.held, self.room, self.continuation = system, held, room, continuation
        self.steps: list[dict[str, Any]] = []
        self.used = 0
        self.refused = ""  # why a finer search was stopped by the memory budget

    def run(
        self,
        out: Any,
        lattices: list[Lattice],
        start: Any = None,
        *,
        grown: bool = False,
        grow: bool = False,
    ) -> Any:
        """``out`` confirmed on ``lattices`` in turn; the first from ``start``'s
        eigenvectors (default: its own). ``grown``: the lattices are grown along the leaks
        (recorded in each step, with its harmonics and whether its outcome was ``kept``).
        ``grow``: where a step leaves clusters open, all far left of the leading exponent,
        the next step is first made on the lattice grown one order along their leaks
        (:func:`~rheolin.floquet.grown.grown_further`), from the eigenvectors the
        verdict holds (``grown`` in the step); kept when it settles every open cluster,
        else its outcome is dropped (``kept`` False) and the standard lattice follows, as
        without it."""
        system = self.system
        w = system.omega
        last: tuple[Lattice, Any] | None = None  # the previous step's lattice and search
        for finer in lattices:
            if not np.any(open_rows(out, w)):
                break
            if grow and last is not None:
                larger = grown_further(out, last[1], last[0], w)  # smaller than finer
                if larger is not None:
                    before = snapshot(out)
                    out, _, ok = self._step(out, larger, None, grown=True)
                    if ok and not np.any(open_rows(out, w)):
                        break
                    out = before  # some stay open: the standard lattice, as without it
                    if ok:
                        self.steps[-1]["kept"] = False
            out, fine, ok = self._step(out, finer, start, grown=grown)
            if not ok:
                break
            start = None
            last = (finer, fine) if fine is not None else None
            if not self.steps[-1]["clusters"]:
                break  # nothing left that a finer lattice could settle
        return out

    def _step(self, out: Any, finer: Lattice, start: Any, *, grown: bool) -> tuple[Any, Any, bool]:
        """One confirmation of ``out``'s open rows on ``finer`` (from ``start``'s
        eigenvectors): ``(out, its search, False when the memory budget stopped it)``."""
        system, continuation = self.system, self.continuation
        clusters = int(open_centres(out, system.omega).size)
        est_finer = lattice_memory(system, finer, clusters=clusters)
        if est_finer > self.room:  # said in the verdict's note when it stays open
            self.refused = (
                f"the search of {clusters} open clusters on the lattice of {len(finer)} "
                f"harmonics needs an estimated {format_bytes(est_finer)}, more than the "
                f"{format_bytes(self.room)} the memory budget leaves it"
            )
            return out, None, False
        self.used = max(self.used, self.held + est_finer)
        previous = continuation.start(system.n, finer) if continuation is not None else None
        try:
            out, fine = confirm_unresolved(
                system, out, finer, previous, start=start, room=self.room
            )
        except MemoryBudgetError as exc:  # more eigenvectors than estimated: out stands
            self.refused = str(exc)
            return out, None, False
        if continuation is not None and fine is not None:
            continuation.keep(system.n, finer, fine)
        step = out.info.pop("confirmed")
        step["harmonics"] = len(finer)
        step["grown"] = grown
        step["kept"] = True
        self.steps.append(step)
        return out, fine, True


def search_result(
    system: PeriodicSystem,
    out: Any,
    lattice: Lattice,
    near: Any,
    used: int,
    t0: float,
    modes: Any = None,
) -> FloquetResult:
    """The :class:`FloquetResult` of a lattice search ``out`` (a band's bodies written in
    their own frames reported at their inertial frequencies)."""
    exponents = large.inertial_exponents(system, modes, out.exponents, out.dominant)
    res = floquet_result(exponents, out.bounds, out.edge, system.omega, "lattice", info=out.info)
    order = np.argsort(-out.exponents.real, kind="stable")
    res.truncation = out.truncation[order]
    res.info["order"] = out.order[order]
    res.info["uncertainty"] = out.uncertainty[order]
    res.dominant = out.dominant[order]
    res.partner = [out.partner[i] for i in order]
    res.complete = out.complete and near is None
    res.lattice = lattice
    res.averaged = out.averaged
    res.averaged_tol = out.averaged_tol
    res.info["memory_estimate"] = used
    res.info["seconds"] = time.perf_counter() - t0
    res.info["centroid"] = out.centroid[order]
    res.info["split_gap"] = out.split_gap[order]
    res.info["unresolved"] = out.unresolved[order]
    res.info["certified"] = out.certified[order]
    for key in ("certified_modes", "certified_radii"):
        res.info[key] = out.info.get(key)
    if "confirmed" in out.info:
        res.info["confirmed"] = out.info["confirmed"]
    res.info["liouville"] = out.liouville
    if isinstance(modes, BandAveraged):
        res.info["band"] = large.band_info(modes, [])
    if order.size:
        res.max_real_uncertainty = leading_uncertainty(out, int(order[0]))
    return res
