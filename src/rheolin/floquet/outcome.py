"""What a lattice search returns: the representatives and their diagnostics."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["LatticeExponents"]


@dataclass
class LatticeExponents:
    """Representatives of the Floquet exponents on a lattice, with their diagnostics.

    ``exponents`` holds one copy per exponent (the one centred on harmonic 0, not folded),
    the conjugates included; the other arrays are aligned with it.
    """

    exponents: np.ndarray
    bounds: np.ndarray
    truncation: np.ndarray
    edge: np.ndarray
    centroid: np.ndarray
    dominant: np.ndarray
    partner: list[tuple[int, int, int]]
    expected: int
    averaged: np.ndarray
    averaged_tol: np.ndarray
    split_gap: np.ndarray
    certified: np.ndarray
    centre: np.ndarray
    unresolved: np.ndarray
    order: np.ndarray
    uncertainty: np.ndarray
    liouville: tuple[float, float]
    info: dict[str, Any] = field(default_factory=dict)
    related: list[list[complex]] = field(default_factory=list)
    radius: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: balanced first-order eigenvectors on ``indices`` (None for a conjugate copy): start
    #: vectors for a search on a finer lattice
    vectors: list[np.ndarray | None] = field(default_factory=list, repr=False)
    indices: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    #: the :class:`~rheolin.harmonics.lattice.Lattice` of ``indices`` (its steps, costs and
    #: shells), on which a refinement grows the lattice along the vectors' leaks
    lattice: Any = field(default=None, repr=False)
    #: the time-averaged modes (:class:`~rheolin.floquet.averaged.Averaged`) the search started from
    modes: Any = field(default=None, repr=False)
    #: truncation estimates not computed yet (``defer_truncation``): ``settle(self, rows)``
    #: fills ``truncation`` and raises ``uncertainty`` on those rows
    settle: Any = field(default=None, repr=False)
    #: per row, a tracked exponent's move per move of its averaged exponent since the
    #: previous call (NaN: not tracked); the next call's prediction
    rate: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=complex))

    @property
    def nbytes(self) -> int:
        """Memory of the eigenvectors it holds [bytes]: its representatives' and those its
        truncation estimates wait with (``settle``)."""
        held = sum(int(v.nbytes) for v in self.vectors if v is not None)
        for _, q, u in getattr(self.settle, "requests", {}).values():
            held += int(q.nbytes) + int(u.nbytes)
        return held

    @property
    def complete(self) -> bool:
        """True when as many exponents were found as the averaged system has."""
        return bool(self.exponents.size >= self.expected)
