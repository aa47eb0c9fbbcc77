"""The lattice ``refine_open`` grows along the leaks of a truncation-open exponent's
eigenvector (``rheolin.floquet.grown.grown_open``), on constructed lattices and vectors: on a
standard lattice it is ``grown_further``'s; from a grown lattice it adds one leaking step
and nothing else; a leak along a dearer step, or a vector it does not hold, grows nothing.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from rheolin.floquet.grown import grown_further, grown_open
from rheolin.harmonics.lattice import Lattice, harmonic_lattice


def vector(lattice: Lattice, energy: dict[int, float]) -> np.ndarray:
    """A one-DOF eigenvector (q then v) with these amplitudes of q on these harmonics."""
    y = np.zeros(2 * len(lattice))
    for h, a in energy.items():
        y[lattice.position(h)] = a
    return y


def held(lattice: Lattice, y: np.ndarray) -> SimpleNamespace:
    """What grown_open reads of a search: its indices and vectors."""
    return SimpleNamespace(indices=lattice.indices, vectors=[y])


def further(lattice: Lattice, y: np.ndarray) -> Lattice:
    """grown_further's lattice for an open (unresolved) exponent far left, vector ``y``."""
    out = SimpleNamespace(
        indices=lattice.indices, exponents=np.array([-1 + 1j, -50 + 5j]), vectors=[None, y],
        unresolved=np.array([False, True]), certified=np.array([False, False]),
        complete=True, centre=np.array([1j, 5j]), related=[[], []],
    )  # fmt: skip
    grown = grown_further(out, out, lattice, 1.0)
    assert grown is not None
    return grown


def test_on_a_standard_lattice_it_is_grown_further() -> None:
    two = harmonic_lattice({3: 1, 7: 1, 50: 2}, 2)
    y = vector(two, {-6: 0.2, -3: 0.3, 0: 0.8, 3: 0.3, 6: 0.2})
    mine = grown_open(held(two, y), np.array([True]), two)
    theirs = further(two, y)
    assert mine is not None
    assert mine.indices.tolist() == theirs.indices.tolist()
    assert mine.indices[mine.boundary].tolist() == theirs.indices[theirs.boundary].tolist()
    assert 9 in mine.indices and 10 in mine.indices and 13 not in mine.indices


def test_from_a_grown_lattice_one_more_leaking_step() -> None:
    two = harmonic_lattice({3: 1, 7: 1, 50: 2}, 2)
    grown = further(two, vector(two, {-6: 0.2, -3: 0.3, 0: 0.8, 3: 0.3, 6: 0.2}))
    y = vector(grown, {-9: 0.2, -6: 0.3, -3: 0.3, 0: 0.8, 3: 0.3, 6: 0.3, 9: 0.2})
    again = grown_open(held(grown, y), np.array([True]), grown)
    assert again is not None
    h = set(again.indices.tolist())
    assert set(grown.indices.tolist()) < h
    # one step of 3 more from every harmonic of the grown lattice: 4 x 3, 7 + 2 x 3
    assert h - set(grown.indices.tolist()) == {-13, -12, -1, 1, 12, 13}
    # nothing new along 7 or 50: no 2 x 7 + 3, 7 + 50, 2 x 50
    assert not h & {17, 11, 57, 100}
    edge = set(again.indices[again.boundary].tolist())
    assert {12, 13, 1, 14, 10, 4, 50} <= edge  # what takes a 7 or a 50 stays the edge
    assert 9 not in edge and 0 not in edge
    # and once more: 5 x 3 (7 + 3 x 3 only where its cost leaves room: not here)
    y2 = vector(again, {-12: 0.2, -9: 0.3, -6: 0.3, 0: 0.8, 6: 0.3, 9: 0.3, 12: 0.2})
    third = grown_open(held(again, y2), np.array([True]), again)
    assert third is not None
    assert set(third.indices.tolist()) - set(again.indices.tolist()) == {-15, 15}


def test_a_dearer_leak_or_no_vector_grows_nothing() -> None:
    two = harmonic_lattice({3: 1, 7: 1, 50: 2}, 2)
    grown = further(two, vector(two, {-6: 0.2, -3: 0.3, 0: 0.8, 3: 0.3, 6: 0.2}))
    # energy on 10 = 7 + 3, the edge along 7 (cost 3 on the grown lattice, 3 costs 2)
    y = vector(grown, {-10: 0.3, -3: 0.3, 0: 0.8, 3: 0.3, 10: 0.3})
    assert grown_open(held(grown, y), np.array([True]), grown) is None
    # a vector on another lattice
    assert grown_open(held(two, vector(two, {0: 1.0, 3: 0.3})), np.array([True]), grown) is None
