"""The stability check of models too large for the dense time-averaged modes: which bodies
to write in their own frames, the memory it needs, and what its result reports
(docs/stability.md, section 8).

A rotating body is written in its own frame (:func:`rheolin.system.frames.rotate`) when its
own coefficients vary on more DOFs than its attachments hold (a non-axisymmetric shaft) and
no gear mesh acts on it: in the inertial frame its high, lightly damped modes couple to the
time variation everywhere along it, in its own frame only through its bearings. A body with
a mesh stays inertial: in its frame the mean mesh stiffness would vary.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..budget import MemoryBudgetError, format_bytes
from ..budget import memory_budget as resolve_budget
from ..harmonics.lattice import system_lattice
from ..system.frames import BodyFrame, rotate, transformation
from ..system.periodic import PeriodicSystem
from .band import BAND_ABOVE, BAND_MODES, BandAveraged, band_memory, band_modes
from .complement import touched_dofs
from .footprint import lattice_memory

__all__ = [
    "DISTRIBUTED",
    "band_estimate",
    "band_failed",
    "band_info",
    "certified_band",
    "frames_to_rotate",
    "in_body_frames",
    "inertial_exponents",
    "inertial_shifts",
]

#: A body whose own time variation touches more DOFs than this is rotated (when unmeshed):
#: three nodes' worth, more than a bearing, a disk or a mesh holds.
DISTRIBUTED = 18


def uses_band(system: PeriodicSystem, band: int | None) -> bool:
    """Whether the stability check takes the band (a large model, or a band asked for)."""
    return band is not None or 2 * system.n > BAND_ABOVE


def frames_to_rotate(system: PeriodicSystem) -> list[BodyFrame]:
    """The bodies of ``system.kept("body_frames")`` to write in their own frames."""
    frames = system.kept("body_frames") or ()
    if not frames or system.constraint is not None:
        return []
    touched = np.zeros(system.n, dtype=bool)
    touched[touched_dofs(system)] = True
    out = []
    for f in frames:
        dofs = np.asarray(f.triples, dtype=np.int64).ravel()
        if f.spin and not f.meshed and int(np.count_nonzero(touched[dofs])) > DISTRIBUTED:
            out.append(f)
    return out


def in_body_frames(system: PeriodicSystem) -> tuple[PeriodicSystem, list[str]]:
    """``system`` with :func:`frames_to_rotate`'s bodies in their frames, and their names."""
    chosen = frames_to_rotate(system)
    if not chosen:
        return system, []
    rotated = rotate(system, chosen)
    rotated.keep("rotated_frames", tuple(chosen))
    return rotated, [f.name for f in chosen]


def inertial_shifts(system: PeriodicSystem, modes: Any) -> np.ndarray:
    """For each band mode of a system in body frames (``system.kept("rotated_frames")``),
    the harmonic ``a`` of ``T(t)`` carrying most of its displacement in the inertial frame:
    an exponent dominated by that mode is reported as its copy ``lambda + i a w1``, whose
    imaginary part is the inertial frequency (zeros when nothing was rotated)."""
    frames = system.kept("rotated_frames")
    if not frames or not isinstance(modes, BandAveraged):
        return np.zeros(getattr(modes, "lam", np.zeros(0)).size, dtype=int)
    n = system.n
    q = modes.X[:n] / modes.sq[:, None]
    T = transformation(n, frames)
    harmonics = sorted(T)
    energy = np.array([np.linalg.norm(T[a] @ q, axis=0) for a in harmonics])
    return np.array(harmonics, dtype=int)[np.argmax(energy, axis=0)]


def band_estimate(system: PeriodicSystem, order: int, modes: int | None = None) -> int:
    """Estimated peak memory [bytes] of the band method at lattice ``order``: the band
    (:func:`~rheolin.floquet.band.band_memory`) and the lattice search on the full operator."""
    lattice = system_lattice(system, order, max_size=10**6)
    return band_memory(system, modes or BAND_MODES) + lattice_memory(system, lattice)


def band_failed(modes: Any) -> bool:
    """Whether ``modes`` is a band whose modes left out are not bounded: no lattice order
    then decides a stable verdict (only an unstable exponent found in the band decides)."""
    if not isinstance(modes, BandAveraged):
        return False
    return modes.complement is None or not modes.complement.certified


def band_info(modes: Any, rotated: list[str]) -> dict[str, Any]:
    """What ``info["band"]`` reports: the band's size and radius, the bodies written in their
    frames, and the certificates of the modes left out."""
    if not isinstance(modes, BandAveraged):
        return {}
    out: dict[str, Any] = {
        "modes": int(modes.lam.size),
        "radius": modes.radius,
        "frames": list(rotated),
        "cpu": dict(modes.cpu),
    }
    if modes.complement is not None:
        out.update(modes.complement.summary())
        # the energy bound: untouched modes outside the band have Re <= 0
        out["complement_max_real"] = 0.0 if modes.complement.energy else float("nan")
    else:
        out.update({"certified": False, "reason": "the modes left out were not bounded"})
    return out


def certified_band(
    system: PeriodicSystem, band: int | None, budget: Any, order: int, start: int | None = None
) -> Any:
    """The certified band of a large model (:func:`~rheolin.floquet.band.band_modes`; its
    size doubling from ``start`` when given), refused with
    :class:`~rheolin.budget.MemoryBudgetError` before anything is built when the first band
    and the lattice search at ``order`` exceed the memory budget (a ``start`` that does not
    fit is dropped), and again before the scan of the last band it can grow to, with the
    lattice its modes ask for (larger than the first estimate's on the gearbox of 50,022
    DOF: 5 harmonics against 3)."""
    from ..linalg.threads import single_thread_blas

    limit = resolve_budget(budget)
    start = None if band is not None else start
    estimate = band_estimate(system, order, band if band is not None else start)
    if start is not None and estimate > limit:  # the smallest band instead
        start = None
        estimate = band_estimate(system, order)

    def refuse(what: str, need: int) -> None:
        if need > limit:
            raise MemoryBudgetError(
                f"the band method ({2 * system.n} first-order DOFs, {what}) needs an estimated "
                f"{format_bytes(need)}, more than the memory budget of {format_bytes(limit)}; "
                "condense bodies (Craig-Bampton) or mesh the shafts more coarsely, or raise "
                "the budget (RHEOLIN_MEMORY_BUDGET or `memory_budget`)"
            )

    refuse(f"lattice order {order}", estimate)

    def fits(modes: BandAveraged) -> None:  # the lattice the band's modes ask for
        from .resonance import floquet_lattice

        lattice = floquet_lattice(system, order, max_size=10**6, avg=modes)
        refuse(
            f"{modes.lam.size} band modes, with its lattice search of order {order}: "
            f"{len(lattice)} harmonics, size {2 * system.n * len(lattice)}",
            band_memory(system, int(modes.lam.size)) + lattice_memory(system, lattice),
        )

    with single_thread_blas():  # many small products: one thread
        return band_modes(system, band, limit, start=start, fits=fits)


def inertial_exponents(
    system: PeriodicSystem, modes: Any, exponents: np.ndarray, dominant: np.ndarray
) -> np.ndarray:
    """``exponents`` of a system in body frames, each moved to the copy of its dominant band
    mode's inertial frequency (:func:`inertial_shifts`); unchanged otherwise."""
    if not isinstance(modes, BandAveraged) or not system.kept("rotated_frames"):
        return exponents
    shift = inertial_shifts(system, modes)
    return exponents + 1j * system.omega * shift[np.clip(dominant, 0, shift.size - 1)]
