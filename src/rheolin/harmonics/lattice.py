"""Harmonic lattices: integer combinations of the coefficient harmonics around 0.

The time variation of a transmission comes from a few sources: each gear mesh (at its mesh
frequency and its multiples) and each shaft (1x from unbalance, 2x from a non-axisymmetric
section). A Floquet eigenvector of the Hill problem lives on integer combinations
``h = a_1 k_1 + ... + a_r k_r`` of these coefficient harmonics, not on every multiple of the
base frequency ``w1`` (input speed / 4757 for a hunting-tooth gearbox).

Each coefficient harmonic is a *step* with a *cost*: 1 for the strongest couplings, one more
for every factor of ten weaker (:func:`coupling_costs`), because an eigenvector's amplitude
falls with the product of the couplings along the way. The lattice of order ``p`` keeps the
harmonics reached from 0 at a total cost of at most ``p`` (docs/stability.md).

>>> lat = harmonic_lattice([3, 7], order=2)
>>> lat.indices.tolist()
[-14, -10, -7, -6, -4, -3, 0, 3, 4, 6, 7, 10, 14]
>>> lat.shell_of(4), lat.describe(4)
(2, '-3 + 7')
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .sets import HarmonicSet

__all__ = [
    "Lattice",
    "coupling_costs",
    "coupling_strengths",
    "harmonic_lattice",
    "lattice_size_bound",
    "system_lattice",
]

#: Couplings weaker than this fraction of the strongest are numerical zeros (no step).
NEGLIGIBLE = 1e-10


@dataclass(frozen=True)
class Lattice:
    """A symmetric harmonic set grown from 0 by weighted steps.

    Attributes
    ----------
    indices
        Sorted harmonic indices (int64), symmetric about 0.
    shell
        For each index, the least total cost that reaches it from 0 (0 at the centre).
    steps
        For each index, one cheapest decomposition into the generators (shape
        ``(len, r)``): ``indices == steps @ generators``.
    generators
        The positive step harmonics ``k_1 < ... < k_r``.
    costs
        The cost of a step by each generator (integers >= 1).
    order
        The lattice order ``p`` (the largest total cost kept).
    """

    indices: np.ndarray
    shell: np.ndarray
    steps: np.ndarray
    generators: tuple[int, ...]
    costs: tuple[int, ...]
    order: int

    def __len__(self) -> int:
        return int(self.indices.size)

    @property
    def harmonics(self) -> HarmonicSet:
        """The indices as a :class:`~rheolin.HarmonicSet`."""
        return HarmonicSet(self.indices)

    @property
    def boundary(self) -> np.ndarray:
        """Mask of the outermost shell (``shell == order``)."""
        return np.asarray(self.shell == self.order)

    def position(self, h: int) -> int:
        """Position of harmonic ``h`` in :attr:`indices` (KeyError when absent)."""
        i = int(np.searchsorted(self.indices, h))
        if i >= self.indices.size or self.indices[i] != h:
            raise KeyError(f"harmonic {h} is not in the lattice")
        return i

    def shell_of(self, h: int) -> int:
        """The shell (cost from 0) of harmonic ``h``."""
        return int(self.shell[self.position(h)])

    def describe(self, h: int, names: Sequence[str] | None = None) -> str:
        """``h`` as a combination of generators, e.g. ``'2 stage1 - intermediate 2x'``.

        ``names`` label the generators (default: their harmonic indices).
        """
        labels = list(names) if names is not None else [str(g) for g in self.generators]
        return combination_text(self.steps[self.position(h)], labels)


def combination_text(coefficients: Sequence[int] | np.ndarray, labels: Sequence[str]) -> str:
    """``'2 a - b'`` from integer coefficients and labels.

    >>> combination_text([2, 0, -1], ["a", "b", "c"])
    '2 a - c'
    """
    parts = []
    for coef, label in zip(coefficients, labels, strict=True):
        if coef == 0:
            continue
        mag = abs(int(coef))
        term = label if mag == 1 else f"{mag} {label}"
        parts.append(("- " if coef < 0 else "+ ") + term)
    if not parts:
        return "0"
    text = " ".join(parts)
    return text[2:] if text.startswith("+ ") else "-" + text[2:]


#: Sizes beyond this are reported as this (no lattice gets near it).
_SIZE_CAP = float(2**62)


def lattice_size_bound(costs: Sequence[int], order: int) -> int:
    """Number of integer vectors ``a`` with ``sum_j costs_j |a_j| <= order``.

    An upper bound of the lattice size (coincident combinations merge), known before the
    lattice is built.

    >>> lattice_size_bound([1] * 5, 2), lattice_size_bound([1] * 5, 3)
    (61, 231)
    >>> lattice_size_bound([1, 2], 2)
    7
    """
    p = int(order)
    # the generating function prod_j (1 + x^c) / (1 - x^c), truncated at x^p: per generator
    # a running sum (1 / (1 - x^c)) and a shifted add (1 + x^c), O(p) each; in floats
    # (exact below 2^53), capped far above any size a lattice may have
    poly = np.zeros(p + 1)
    poly[0] = 1.0
    for c in costs:
        c = int(c)
        if c > p:
            continue
        for start in range(c):  # b[i] = a[i] + b[i - c]
            poly[start::c] = np.cumsum(poly[start::c])
        poly[c:] = poly[c:] + poly[:-c].copy()
        np.minimum(poly, _SIZE_CAP, out=poly)
    return int(min(float(poly.sum()), _SIZE_CAP))


def coupling_strengths(system: Any) -> dict[int, float]:
    """Strength of each positive coefficient harmonic ``k``, in the balanced Hill pencil.

    ``||Tv K_k Tq||_1 + ||Tv D_k Tv||_1 + w_ref ||Tv M_k Tv||_1`` with the balancing of
    :func:`rheolin.harmonics.hill.state_scaling` (all terms in rad/s) and ``w_ref`` the median local
    frequency ``sqrt(k_ii / m_ii)``.
    """
    from .hill import state_scaling

    sq, sv = state_scaling(system)
    iq, iv = 1.0 / sq, 1.0 / sv
    w_ref = float(np.median(sq / sv))
    out: dict[int, float] = {}
    for k in system.coefficient_harmonics:
        if k <= 0:
            continue

        def part(table: dict, right: np.ndarray, k: int = k) -> float:
            x = table.get(k)
            return 0.0 if x is None else _scaled_norm1(x, iv, right)

        out[int(k)] = part(system.K, iq) + part(system.D, iv) + w_ref * part(system.M, iv)
    return out


def _scaled_norm1(x: Any, left: np.ndarray, right: np.ndarray) -> float:
    """``||diag(left) x diag(right)||_1`` (largest column sum), from the entries."""
    from .hill import scaled_entries

    _, c, v = scaled_entries(x, left, right)
    return float(np.bincount(c, np.abs(v), minlength=np.shape(x)[1]).max()) if v.size else 0.0


def coupling_costs(system: Any) -> dict[int, int]:
    """Step cost of each positive coefficient harmonic: ``1 + floor(log10(c_max / c_k))``.

    Couplings within a factor of ten of the strongest cost one step; a hundred times weaker,
    three... Numerical zeros (below ``NEGLIGIBLE c_max``) are left out.

    >>> import numpy as np, rheolin as rl
    >>> s = rl.PeriodicSystem(1.0, M={0: np.eye(1)}, K={0: np.eye(1), 2: 0.1 * np.eye(1),
    ...                       3: 0.005 * np.eye(1)})
    >>> coupling_costs(s)
    {2: 1, 3: 2}
    """
    strengths = coupling_strengths(system)
    if not strengths:
        return {}
    top = max(strengths.values())
    if top <= 0:
        return {}
    out = {}
    for k, c in sorted(strengths.items()):
        if c <= NEGLIGIBLE * top:
            continue
        out[k] = 1 + int(np.floor(np.log10(top / c) + 1e-9))
    return out


def harmonic_lattice(
    generators: Iterable[int] | Mapping[int, int],
    order: int,
    *,
    max_size: int | None = None,
) -> Lattice:
    """The lattice of harmonics within a total step cost ``order`` of 0.

    Parameters
    ----------
    generators
        Step harmonics (cost 1 each), or a mapping ``{harmonic: cost}``.
    order
        The largest total cost ``p``.
    max_size
        Refuse (``ValueError``) when :func:`lattice_size_bound` exceeds it, before building.

    Examples
    --------
    One generator gives the dense grid on its multiples:

    >>> harmonic_lattice([2], 3).indices.tolist()
    [-6, -4, -2, 0, 2, 4, 6]
    >>> harmonic_lattice({1: 1, 10: 2}, 2).indices.tolist()
    [-10, -2, -1, 0, 1, 2, 10]
    """
    if isinstance(order, bool) or not isinstance(order, int | np.integer) or order < 0:
        raise ValueError(f"`order` must be a non-negative integer, got {order!r}")
    table: dict[int, int] = {}
    items = generators.items() if isinstance(generators, Mapping) else ((g, 1) for g in generators)
    for g, c in items:
        g, c = abs(int(g)), int(c)
        if g == 0:
            continue
        if c < 1:
            raise ValueError(f"step costs must be integers >= 1, got {c} for harmonic {g}")
        table[g] = min(c, table.get(g, c))
    gens = sorted(table)
    costs = [table[g] for g in gens]
    bound = lattice_size_bound(costs, int(order))
    if max_size is not None and bound > max_size:
        raise ValueError(
            f"a lattice of order {order} on {len(gens)} generators may hold {bound} harmonics "
            f"(more than {max_size}); lower the order"
        )
    r = len(gens)
    step_of: dict[int, np.ndarray] = {0: np.zeros(r, dtype=np.int64)}
    shell: dict[int, int] = {0: 0}
    levels: dict[int, list[int]] = {0: [0]}
    unit = np.eye(r, dtype=np.int64)
    for level in range(int(order) + 1):
        for h in levels.get(level, []):
            if shell[h] != level:
                continue  # reached more cheaply later in the same sweep (cannot happen) or stale
            for j, (g, c) in enumerate(zip(gens, costs, strict=True)):
                nxt = level + c
                if nxt > order:
                    continue
                for sign in (1, -1):
                    m = h + sign * g
                    if m not in shell or shell[m] > nxt:
                        shell[m] = nxt
                        step_of[m] = step_of[h] + sign * unit[j]
                        levels.setdefault(nxt, []).append(m)
    idx = np.array(sorted(shell), dtype=np.int64)
    steps = np.array([step_of[int(h)] for h in idx], dtype=np.int64).reshape(idx.size, r)
    shells = np.array([shell[int(h)] for h in idx], dtype=np.int64)
    for arr in (idx, steps, shells):
        arr.setflags(write=False)
    return Lattice(idx, shells, steps, tuple(gens), tuple(costs), int(order))


def system_lattice(system: Any, order: int, *, max_size: int | None = None) -> Lattice:
    """The lattice of ``system`` with the costs of :func:`coupling_costs`.

    >>> import numpy as np, rheolin as rl
    >>> s = rl.PeriodicSystem(2.0, M={0: np.eye(1)}, K={0: np.eye(1), 1: -0.2 * np.eye(1)})
    >>> system_lattice(s, 3).indices.tolist()
    [-3, -2, -1, 0, 1, 2, 3]
    """
    costs = coupling_costs(system)
    if not costs:
        return harmonic_lattice({}, 0)
    return harmonic_lattice(costs, order, max_size=max_size)
