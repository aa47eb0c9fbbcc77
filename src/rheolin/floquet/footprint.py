"""Memory footprint of the lattice search, estimated before anything is built."""

from __future__ import annotations

import numpy as np

from ..harmonics.blocks import coefficient_blocks
from ..harmonics.lattice import Lattice
from ..system.periodic import PeriodicSystem
from .band import BAND_ABOVE
from .search import ARNOLDI_STEPS
from .shift_invert import LU_FILL

__all__ = [
    "CANDIDATES_PER_CLUSTER",
    "CHOOSING_PER_CLUSTER",
    "HELD_PER_CLUSTER",
    "TYPICAL_CLUSTERS",
    "lattice_memory",
    "search_vectors",
]


#: Eigenvectors over the lattice a search keeps per cluster it searches, until the
#: representatives are chosen: its candidates, the converged Ritz pairs of its last
#: checkpoint (3.3 on average on the 126-DOF gearbox, at most 23; 3.6 on the 4,986-DOF
#: gearbox at lattice order 2).
CANDIDATES_PER_CLUSTER = 4

#: ... and beside them, while the representatives are chosen (the Arnoldi basis freed):
#: each representative's unit copy and its conjugate's (one or two representatives per
#: cluster).
CHOOSING_PER_CLUSTER = 2

#: What a finished search still holds per cluster: its representatives' polished vectors and
#: the halves their truncation estimates wait with.
HELD_PER_CLUSTER = 3

#: Clusters a full search is taken to search before its averaged modes are known: the
#: 126-DOF gearbox searches 35-38 (the rest certified by their Gershgorin discs), the
#: 4,986-DOF gearbox's band 35. The search checks the count it finds
#: (:class:`~rheolin.floquet.search.LatticeSearch`, ``room``).
TYPICAL_CLUSTERS = 40


def lattice_memory(
    system: PeriodicSystem,
    lattice: Lattice,
    k: int = 8,
    *,
    searching: bool = True,
    clusters: int | None = None,
) -> int:
    """Estimated peak memory [bytes] of :func:`lattice_exponents` on ``lattice``.

    Counted without building anything: the entries of the lattice operator (from the block
    patterns and the number of harmonic pairs each coefficient harmonic couples), its LU at
    :data:`~rheolin.floquet.shift_invert.LU_FILL` times those entries, the Arnoldi basis,
    and the dense averaged modes (a large model's band:
    :func:`~rheolin.floquet.band.band_memory`, counted by the caller). ``searching=False``:
    what a finished search still holds while finer lattices are searched near its open
    clusters (the operator, its vectors and the averaged modes; no LU, no Arnoldi basis).
    ``clusters``: the clusters the search is to search (:func:`search_vectors`; default
    :data:`TYPICAL_CLUSTERS`, a confirmation near a few clusters passes their count).
    """
    H = lattice.indices
    n = system.n
    nnz = 0
    for k_h, block in coefficient_blocks(system).items():
        pos = np.minimum(np.searchsorted(H, H + k_h), H.size - 1)
        pairs = int(np.count_nonzero(H[pos] == H + k_h))
        if not pairs:
            continue
        nnz += pairs * int(block.entries()[0].size)
    size2 = 2 * n * H.size
    # the Arnoldi basis (no restarts) and its converged Ritz vectors, at most one per basis
    # vector (under tracemalloc, the peak of a 9,954-DOF gearbox verdict is such a search)
    ncv = 2 * max(2 * k + 1, ARNOLDI_STEPS[-1] + 1)
    averaged = (2 * n) ** 2 * 16 * 6 if 2 * n <= BAND_ABOVE else 0
    c = TYPICAL_CLUSTERS if clusters is None else max(int(clusters), 0)
    if not searching:
        return int(nnz * 16 * 6 + size2 * 16 * (8 + HELD_PER_CLUSTER * c) + averaged)
    vectors = 8 + search_vectors(c, ncv)
    return int(nnz * 16 * (6 + LU_FILL) + size2 * 16 * vectors + averaged + 64 * 2**20)


def search_vectors(clusters: int, basis: int) -> int:
    """Eigenvectors over the lattice a search of ``clusters`` clusters holds at its peak,
    with an Arnoldi ``basis`` of that many vectors (its Ritz vectors included): the basis
    beside the candidates found so far, or the candidates beside the copies made while the
    representatives are chosen (under tracemalloc, the 4,986-DOF gearbox at lattice order 2,
    27 harmonics, 35 clusters and 131 candidates: 1.10 GB at the peak against an estimate
    of 1.58 GB; bench/search_memory.py).

    >>> search_vectors(36, 110), search_vectors(100, 110)
    (254, 600)
    """
    pool = CANDIDATES_PER_CLUSTER * clusters
    return int(max(basis + pool, pool + CHOOSING_PER_CLUSTER * clusters))
