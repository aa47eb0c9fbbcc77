"""The lattices a confirmation grows along the steps its open eigenvectors leak to, where
they all lie far left of the leading exponent (docs/stability.md, section 4): from the
coarsest lattice (:func:`grown_lattice`), and one order further from a confirmation's
(:func:`grown_further`)."""

from __future__ import annotations

import dataclasses

import numpy as np

from ..harmonics.lattice import Lattice
from .confirm import cluster_members, lattice_order, open_rows, short_rows
from .outcome import LatticeExponents
from .shift_invert import harmonic_energy

__all__ = ["FAR", "LEAK_ENERGY", "far_open", "grown_further", "grown_lattice", "grown_open"]


#: A step of the coarse lattice is a direction the open eigenvectors leak to when its two
#: harmonics (``+g`` and ``-g``) carry at least this fraction of one of their energies (and
#: each vector's strongest step is one): the first confirmation grows the lattice along
#: those steps only (:func:`grown_lattice`; bench/stability.py, design notes).
LEAK_ENERGY = 0.05

#: The lattice grown along the leaks is used only when every open exponent lies this many
#: times further left than the leading one
#: (the heavily damped modes a shaft's 2x mixes with their copies): near the axis a lattice
#: grown along the leaks can miss an exponent the next order holds (the gear variant inside
#: its principal range lost its growing exponent so, tests/stability/test_runup_edge.py).
FAR = 5.0


def grown_lattice(out: LatticeExponents, lattice: Lattice, w: float) -> Lattice | None:
    """The lattice a confirmation from the coarsest lattice starts on when every open
    exponent lies far left of the leading one (None: not that case).

    From the coarsest lattice (order 1, the default start), the finer one grows only along the
    steps the open eigenvectors leak to (:data:`LEAK_ENERGY`): those keep their cost, every
    other generator costs one more, and the order is 2. It holds the coarse lattice (a single
    step costs at most 2) and every combination of two leaking steps; on the gearbox 15-29
    harmonics where order 2 has 35-61. What it leaves out stays in each finer exponent's
    truncation estimate (the harmonics one step outside), as for any lattice. Not from a
    finer coarse lattice, nor when a cluster is short of exponents (the missing one has no
    eigenvector to say where it lives) or an open row has none.

    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from rheolin.harmonics.lattice import harmonic_lattice
    >>> coarse = harmonic_lattice({3: 1, 7: 1, 50: 2}, 1)
    >>> coarse.indices.tolist()
    [-7, -3, 0, 3, 7]
    >>> y = np.zeros(2 * 5)  # one DOF: q then v on the 5 harmonics; energy on 0 and +-3
    >>> y[[1, 2, 3]] = [0.4, 0.8, 0.4]
    >>> out = SimpleNamespace(  # a resolved leading exponent, an open one far left of it
    ...     indices=coarse.indices, exponents=np.array([-1 + 1j, -50 + 5j]), vectors=[None, y],
    ...     unresolved=np.array([False, True]), certified=np.array([False, False]),
    ...     complete=True, centre=np.array([1j, 5j]), related=[[], []])
    >>> fine = grown_lattice(out, coarse, 1.0)
    >>> dict(zip(fine.generators, fine.costs)), fine.indices.tolist()
    ({3: 1, 7: 2, 50: 3}, [-7, -6, -3, 0, 3, 6, 7])
    """
    if lattice.order != 1:
        return None
    rows = far_open(out, w)
    if rows is None:
        return None  # an open cluster near the axis: the whole next order
    todo = open_rows(out, w)
    H = np.asarray(out.indices)
    nh = H.size
    singles = {
        g: np.flatnonzero(np.isin(H, (g, -g)))
        for g, c in zip(lattice.generators, lattice.costs, strict=True)
        if c == 1
    }
    if not singles:
        return None
    vectors = [
        (out.vectors[i], bool(todo[i]) and out.centre[i].imag >= 0) for i in np.flatnonzero(rows)
    ]
    leaking = _leaking(vectors, singles, nh)
    if not leaking:
        return None
    costs = {
        g: c if g in leaking else c + 1
        for g, c in zip(lattice.generators, lattice.costs, strict=True)
    }
    return _smaller(lattice, 2, costs)


def far_open(out: LatticeExponents, w: float) -> np.ndarray | None:
    """The open rows of ``out`` with the clusters they share their quota with, when every
    one lies :data:`FAR` times further left than the leading exponent and no cluster is
    short of exponents (None otherwise: an open cluster near the axis, or a missing
    exponent, which the standard next order is to settle)."""
    if short_rows(out, w).any():
        return None
    todo = open_rows(out, w)
    rows = todo.copy()
    for z in {z for i in np.flatnonzero(todo) for z in out.related[i]}:
        rows |= cluster_members(out.centre, z, w)
    lead = float(out.exponents.real.max(initial=-np.inf))
    if not (lead < 0 and np.all(out.exponents.real[rows] < FAR * lead)):
        return None
    return rows


def grown_further(
    out: LatticeExponents, fine: LatticeExponents, lattice: Lattice, w: float
) -> Lattice | None:
    """The lattice one order above ``lattice`` grown along the leaks of the clusters a
    confirmation on ``lattice`` left open, when every one lies far left of the leading
    exponent (:func:`far_open`; None: not that case, a leak along a step ``lattice`` holds
    at a cost above 1, which one more order would not extend, or nothing saved against the
    standard next order).

    ``fine``: that confirmation's search (the open clusters' eigenvectors on ``lattice``);
    ``out``: the verdict's exponents after it. A step is leaking when the harmonics of the
    outer shell of ``lattice`` (order ``q``) that take it carry at least
    :data:`LEAK_ENERGY` of an open eigenvector's energy (and each vector's strongest step
    is one). Leaking steps cost ``q``, every other step ``c (q + 1)``, in a lattice of order
    ``q (q + 1)``: the order-``q`` lattice and every combination of ``q + 1`` leaking steps.
    Its outer shell, which the resolution test reads, is its top cost and every harmonic of
    the order-``q`` outer shell that takes a step that is not leaking: the grown lattice
    extends those only along the leaks, so they stay its edge.

    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from rheolin.harmonics.lattice import harmonic_lattice
    >>> two = harmonic_lattice([3, 7], 2)
    >>> two.indices.tolist()
    [-14, -10, -7, -6, -4, -3, 0, 3, 4, 6, 7, 10, 14]
    >>> y = np.zeros(2 * 13)  # one DOF: q then v; energy on 0, +-3 and +-6
    >>> y[[3, 5, 6, 7, 9]] = [0.2, 0.3, 0.8, 0.3, 0.2]
    >>> out = SimpleNamespace(
    ...     indices=two.indices, exponents=np.array([-1 + 1j, -50 + 5j]), vectors=[None, y],
    ...     unresolved=np.array([False, True]), certified=np.array([False, False]),
    ...     complete=True, centre=np.array([1j, 5j]), related=[[], []])
    >>> fine = grown_further(out, out, two, 1.0)
    >>> fine.indices.tolist()
    [-14, -10, -9, -7, -6, -4, -3, 0, 3, 4, 6, 7, 9, 10, 14]
    >>> fine.indices[fine.boundary].tolist()  # 3 x 3, and what takes a step of 7
    [-14, -10, -9, -4, 4, 9, 10, 14]
    """
    rows = far_open(out, w)
    if rows is None:
        return None
    H = np.asarray(lattice.indices)
    if not np.array_equal(np.asarray(fine.indices), H):
        return None
    nh, q = H.size, lattice.order
    outer, uses = _outer_steps(lattice, q)
    if not uses:
        return None
    centres = out.centre[rows]
    mine = np.zeros(fine.exponents.size, dtype=bool)
    for z in centres[np.isfinite(centres)]:
        mine |= cluster_members(fine.centre, z, w)
    # (the search keeps the vectors of the upper half plane's representatives)
    upper = fine.centre.imag >= -1e-9 * np.maximum(np.abs(fine.centre), w)
    leaking = _leaking([(fine.vectors[i], bool(upper[i])) for i in np.flatnonzero(mine)], uses, nh)
    cost = dict(zip(lattice.generators, lattice.costs, strict=True))
    if not leaking or any(cost[g] != 1 for g in leaking):
        return None  # a leak one more order would not extend: the standard next order
    top = q * (q + 1)
    grown = _smaller(
        lattice, top, {g: q if g in leaking else c * (q + 1) for g, c in cost.items()}, q + 1
    )
    if grown is None:
        return None
    return _keep_edge(grown, lattice, outer, leaking)


def grown_open(out: LatticeExponents, rows: np.ndarray, lattice: Lattice) -> Lattice | None:
    """The lattice ``lattice`` grown one step further along the leaks of the eigenvectors
    of the rows ``rows`` (mask) of ``out``, which holds them on ``lattice``
    (:func:`~rheolin.floquet.accuracy.refine_open`: exponents resolved there whose
    truncation estimates keep the verdict open; None: a row without its vector, no leak, a
    leak along a step that does not have the lattice's cheapest cost, or nothing grown).

    A step is leaking when the harmonics of the outer shell of ``lattice`` (cost ``T``) that
    take it carry at least :data:`LEAK_ENERGY` of a vector's energy (and each vector's
    strongest step is one), as in :func:`grown_further`, which this is on a standard
    lattice. With ``d`` the cheapest step cost, leaking steps cost ``c T``, every other step
    ``c (T + d)``, in a lattice of order ``T (T + d)``: it holds ``lattice``, every
    combination of leaking steps alone one step longer, and those with other steps where
    their cost leaves room. (Not reduced by the
    costs' common divisor: its order stays above the standard orders a refinement raises a
    cluster to, like :func:`grown_further`'s, so its exponents are not taken for those.)
    A lattice grown along the leaks grows again so (its leaking steps are its cheapest). A
    leak along a dearer step is not grown (one more step of ``d`` would not extend it). The
    harmonics of the outer shell that take a step that is not leaking stay the edge.

    The lattice :func:`grown_further` grows from order 2 of the steps 3 and 7 along 3 (its
    edge 3 x 3, 2 x 7 and the order-2 shell that takes a 7), grown again along 3:

    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from rheolin.harmonics.lattice import harmonic_lattice
    >>> two = harmonic_lattice([3, 7], 2)
    >>> y = np.zeros(2 * 13)  # as in grown_further: energy on 0, +-3 and +-6 of order 2
    >>> y[[3, 5, 6, 7, 9]] = [0.2, 0.3, 0.8, 0.3, 0.2]
    >>> out = SimpleNamespace(
    ...     indices=two.indices, exponents=np.array([-1 + 1j, -50 + 5j]), vectors=[None, y],
    ...     unresolved=np.array([False, True]), certified=np.array([False, False]),
    ...     complete=True, centre=np.array([1j, 5j]), related=[[], []])
    >>> grown = grown_further(out, out, two, 1.0)
    >>> dict(zip(grown.generators, grown.costs)), grown.order
    ({3: 2, 7: 3}, 6)
    >>> grown.indices.tolist(), grown.indices[grown.boundary].tolist()
    ([-14, -10, -9, -7, -6, -4, -3, 0, 3, 4, 6, 7, 9, 10, 14], [-14, -10, -9, -4, 4, 9, 10, 14])
    >>> y = np.zeros(2 * 15)  # one DOF: q then v; energy on 0, +-3, +-6 and +-9
    >>> y[[2, 4, 6, 7, 8, 10, 12]] = [0.2, 0.3, 0.3, 0.8, 0.3, 0.3, 0.2]
    >>> out = SimpleNamespace(indices=grown.indices, vectors=[y])
    >>> finer = grown_open(out, np.array([True]), grown)
    >>> dict(zip(finer.generators, finer.costs)), finer.order
    ({3: 12, 7: 24}, 48)
    >>> finer.indices.tolist()  # +-12, and 7 - 6, 7 + 6 (one step of 3 more)
    [-14, -13, -12, -10, -9, -7, -6, -4, -3, -1, 0, 1, 3, 4, 6, 7, 9, 10, 12, 13, 14]
    >>> finer.indices[finer.boundary].tolist()  # 4 x 3, 7 +- 2 x 3, and what takes a 7
    [-14, -13, -12, -10, -4, -1, 1, 4, 10, 12, 13, 14]

    Energy on 10 = 7 + 3 leaks along 7, which costs more than 3 on ``grown``: not grown.

    >>> y[[1, 13]] = 0.3
    >>> grown_open(out, np.array([True]), grown) is None
    True
    """
    H = np.asarray(lattice.indices)
    if not np.array_equal(np.asarray(out.indices), H):
        return None
    nh, top = H.size, int(lattice.order)
    outer, uses = _outer_steps(lattice, top)
    if not uses:
        return None
    leaking = _leaking([(out.vectors[i], True) for i in np.flatnonzero(rows)], uses, nh)
    cost = dict(zip(lattice.generators, lattice.costs, strict=True))
    d = min(cost.values())
    if not leaking or any(cost[g] != d for g in leaking):
        return None
    costs = {g: c * top if g in leaking else c * (top + d) for g, c in cost.items()}
    grown = lattice_order(lattice, top * (top + d), costs)
    if grown is None or len(grown) <= nh:
        return None
    return _keep_edge(grown, lattice, outer, leaking)


def _outer_steps(lattice: Lattice, top: int) -> tuple[np.ndarray, dict[int, np.ndarray]]:
    """The outer shell of ``lattice`` (cost ``top``, a mask) and, per step, the positions
    of its harmonics that take that step (steps that none takes left out)."""
    steps = np.asarray(lattice.steps)
    outer = np.asarray(lattice.shell) == top
    uses = {g: np.flatnonzero(outer & (steps[:, j] != 0)) for j, g in enumerate(lattice.generators)}
    return outer, {g: at for g, at in uses.items() if at.size}


def _keep_edge(grown: Lattice, lattice: Lattice, outer: np.ndarray, leaking: set[int]) -> Lattice:
    """``grown`` with the harmonics of ``lattice``'s outer shell that take a step not
    ``leaking`` set to its top cost: grown only along the leaks, they stay its edge."""
    H = np.asarray(lattice.indices)
    steps = np.asarray(lattice.steps)
    other = np.array([g not in leaking for g in lattice.generators])
    edge = H[outer & np.any(steps[:, other] != 0, axis=1)] if other.any() else H[:0]
    shell = np.asarray(grown.shell).copy()
    shell[np.isin(grown.indices, edge)] = grown.order
    return dataclasses.replace(grown, shell=shell)


def _leaking(
    vectors: list[tuple[np.ndarray | None, bool]], uses: dict[int, np.ndarray], nh: int
) -> set[int] | None:
    """The steps open eigenvectors leak to: each vector's strongest and those carrying at
    least :data:`LEAK_ENERGY` of its energy on the harmonics ``uses[g]`` of step ``g``
    (``vectors``: each with whether its leak must be known; None when such a one has no
    vector)."""
    leaking: set[int] = set()
    for y, needed in vectors:
        if y is None:
            if needed:
                return None  # an open row whose leak is not known
            continue
        e = harmonic_energy(y, y.size // (2 * nh), nh)
        total = float(e.sum())
        if total <= 0:
            continue
        share = {g: float(e[at].sum()) / total for g, at in uses.items()}
        leaking.add(max(share, key=lambda g: share[g]))
        leaking.update(g for g, s in share.items() if s >= LEAK_ENERGY)
    return leaking


def _smaller(
    lattice: Lattice, order: int, costs: dict[int, int], standard: int | None = None
) -> Lattice | None:
    """The lattice of ``order`` with ``costs``, when it is smaller than the standard one of
    order ``standard`` (default ``order``) on ``lattice``'s steps (None: nothing saved)."""
    grown = lattice_order(lattice, order, costs)
    plain = lattice_order(lattice, order if standard is None else standard)
    if grown is None or (plain is not None and len(grown) >= len(plain)):
        return None  # nothing saved: the standard orders
    return grown
