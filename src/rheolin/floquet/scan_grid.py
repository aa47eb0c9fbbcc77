"""The frequencies the small-gain scan of a band's modes left out visits, and in which order
(docs/stability.md, 8.3): an octave grid above half the band's radius, steps of a fraction of
the distance to the nearest pole the loop can have below it, the points just above the radius
first.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "EDGE_SPAN",
    "PER_OCTAVE",
    "QUIET",
    "SPACING",
    "coarse_to_fine",
    "scan_grid",
    "visiting_order",
]

#: Scan points per octave between the smallest and the largest frequency of the pencil.
PER_OCTAVE = 3

#: The octave grid's step as a fraction of the frequency, ``2^(1/PER_OCTAVE) - 1``.
SPACING = 2.0 ** (1.0 / PER_OCTAVE) - 1.0

#: Below this fraction of the band's radius ``R`` the loop of the modes left out has no pole
#: nearer than ``(1 - QUIET) R`` (every eigenvalue inside the radius is a band mode): the scan
#: spaces its points there by the grid's fraction of that distance, not of the frequency, and
#: goes to no time-averaged eigenvalue it finds there (:func:`scan_grid`).
QUIET = 0.5

#: Points of the scan between the band's radius and this many times it are visited first: the
#: loop of a band too small for its limit peaks there, just above the radius.
EDGE_SPAN = 4.0


def scan_grid(low: float, top: float, radius: float) -> np.ndarray:
    """The scan's frequencies from ``low`` to ``top`` [rad/s] for a band of ``radius``:
    the points of a grid of :data:`PER_OCTAVE` an octave from :data:`QUIET` times the radius
    up, and below it steps of the same fraction (:data:`SPACING`) of the distance
    ``radius - omega`` to the nearest pole the loop can have there.

    >>> scan_grid(1.0, 64.0, 0.0).size  # no band: 3 an octave over 6 octaves
    18
    >>> g = scan_grid(1.0, 1e4, 1e3)
    >>> g[:4].round(1).tolist(), g.size  # 3 points below 500 rad/s, where 30 were geometric
    ([1.0, 260.7, 452.8, 587.8], 16)
    """
    count = max(int(np.ceil(PER_OCTAVE * np.log2(max(top / low, 2.0)))), 2)
    octaves = np.geomspace(low, top, count)
    quiet: list[float] = []
    omega = float(low)
    while omega < QUIET * radius:
        quiet.append(omega)
        omega += SPACING * (radius - omega)
    # the octave grid's own points above: the eigenvalues the scan goes to are found from them
    return np.concatenate([quiet, octaves[octaves >= QUIET * radius]])


def visiting_order(grid: np.ndarray, radius: float) -> np.ndarray:
    """The order the scan visits ``grid`` in: its first point, then the points between the
    band's radius and :data:`EDGE_SPAN` times it, then the rest, each part coarse to fine
    (:func:`coarse_to_fine`): a failing band is found failing in a few points.

    >>> visiting_order(np.array([0.1, 1.0, 2.0, 4.0, 8.0, 16.0]), 1.5).tolist()
    [0, 2, 3, 4, 1, 5]
    """
    order = coarse_to_fine(grid.size)
    rank = np.where((grid[order] >= radius) & (grid[order] <= EDGE_SPAN * radius), 0, 1)
    rank[order == 0] = -1
    return np.asarray(order[np.argsort(rank, kind="stable")])


def coarse_to_fine(count: int) -> np.ndarray:
    """The indices ``0 .. count-1``, every 16th first, then every 8th, ... then the rest.

    >>> coarse_to_fine(5).tolist()
    [0, 4, 2, 1, 3]
    """
    order = np.arange(count)
    level = np.zeros(count, dtype=int)
    for stride in (2, 4, 8, 16):
        level[order % stride == 0] -= 1
    return np.asarray(order[np.argsort(level, kind="stable")])
