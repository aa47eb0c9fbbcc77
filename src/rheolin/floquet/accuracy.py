"""Accuracy on demand: the largest real part refined to a relative tolerance.

A verdict needs each exponent only on the right side of the axis; the largest real part (the
growth rate variants are compared by) comes with the uncertainty of its lattice,
``TRUNCATION_SAFETY`` times its truncation estimate: about 1e-3 relative near a resonance on
an order-1 lattice. :func:`refine_leading` searches the leading exponent's cluster again on
finer lattices, near it only (:func:`~rheolin.floquet.confirm.confirm_unresolved` with its
rows), until its stated uncertainty meets ``rtol |max_real|``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..budget import memory_budget as resolve_budget
from ..harmonics.lattice import Lattice, harmonic_lattice
from ..system.periodic import PeriodicSystem
from .confirm import confirm_unresolved, snapshot
from .outcome import LatticeExponents
from .result import SAFETY
from .search import lattice_memory

__all__ = [
    "DEFAULT_RTOL",
    "RTOL_ORDERS",
    "ZETA_FLOOR",
    "leading_uncertainty",
    "next_lattice",
    "refine_leading",
    "target",
]

#: Relative accuracy of the largest real part that :func:`rheolin.floquet` meets by default.
DEFAULT_RTOL = 1e-4

#: At most this many refinement steps (lattice orders) per verdict.
RTOL_ORDERS = 3

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
    info: dict[str, Any] = {"rtol": float(rtol), "orders": [], "met": False}
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
        finer = _order(lattice, order)
        if finer is None or lattice_memory(system, finer) > limit:
            break
        previous = continuation.start(n, finer) if continuation is not None else None
        before = snapshot(out)
        out, fine = confirm_unresolved(system, out, finer, previous, todo=todo)
        out.info.pop("confirmed", None)
        info["orders"].append(order)
        if continuation is not None and fine is not None:
            continuation.keep(n, finer, fine)
        j = int(np.argmax(out.exponents.real))
        if leading_uncertainty(out, j) >= unc:  # not better: keep the coarse exponents
            out = before
    return out, info


def _cluster_rows(out: LatticeExponents, row: int, w: float) -> np.ndarray:
    """Rows of ``row``'s cluster (its centre and the conjugate centre)."""
    z = out.centre[row]
    if not np.isfinite(z):
        mask = np.zeros(out.exponents.size, dtype=bool)
        mask[row] = True
        return mask
    tol = 1e-9 * max(abs(z), w)
    return (np.abs(out.centre - z) <= tol) | (np.abs(out.centre - np.conj(z)) <= tol)


def next_lattice(lattice: Lattice) -> Lattice | None:
    """The lattice of the next order with the same steps (None past a million harmonics)."""
    return _order(lattice, lattice.order + 1)


def _order(lattice: Lattice, order: int) -> Lattice | None:
    steps = dict(zip(lattice.generators, lattice.costs, strict=True))
    if not steps:
        return None
    try:
        return harmonic_lattice(steps, order, max_size=10**6)
    except ValueError:
        return None
