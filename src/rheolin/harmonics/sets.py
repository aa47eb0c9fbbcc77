"""Harmonic sets: the symmetric sets of integers ``n`` in ``q(t) = sum_n q_n exp(i n w1 t)``."""

from __future__ import annotations

import warnings
from collections.abc import Iterable
from typing import Any

import numpy as np

__all__ = ["HarmonicSet", "TruncationWarning", "as_harmonic_set"]


class TruncationWarning(UserWarning):
    """A frequency cut-off leaves out harmonics at which the system is loaded.

    The response to those load harmonics is then not computed at all, and through the
    time-varying coefficients it also misses from the harmonics that are kept.
    """


class HarmonicSet:
    """A symmetric, sorted set of harmonic indices.

    Parameters
    ----------
    indices
        Integers; the set is symmetrized (``n`` and ``-n``), sorted and made unique.

    Examples
    --------
    >>> HarmonicSet([3, 1]).indices
    array([-3, -1,  1,  3])
    >>> len(HarmonicSet.full(2))
    5
    """

    __slots__ = ("_indices",)

    def __init__(self, indices: Iterable[int]) -> None:
        arr = np.asarray(list(indices))
        if arr.size == 0:
            raise ValueError("`harmonics` must contain at least one index")
        if arr.dtype.kind not in "iu":
            if arr.dtype.kind == "f" and np.all(arr == np.round(arr)):
                arr = arr.astype(np.int64)
            else:
                raise ValueError(f"`harmonics` must be integers, got dtype {arr.dtype}")
        arr = arr.astype(np.int64).ravel()
        self._indices = np.unique(np.concatenate([arr, -arr]))
        self._indices.setflags(write=False)

    @classmethod
    def full(cls, N: int) -> HarmonicSet:
        """The dense set ``-N..N``.

        >>> HarmonicSet.full(1).indices
        array([-1,  0,  1])
        """
        if isinstance(N, bool) or not isinstance(N, int | np.integer) or N < 0:
            raise ValueError(f"`N` must be a non-negative integer, got {N!r}")
        return cls(range(-int(N), int(N) + 1))

    @classmethod
    def closure(
        cls,
        system: Any,
        order: int = 2,
        max_harmonic: int | None = None,
        generators: Iterable[int] | None = None,
        max_size: int | None = None,
    ) -> HarmonicSet:
        """Grow a set from the load harmonics by the coefficient harmonics (docs/conventions.md,
        harmonic sets).

        Start at the system's load harmonics ``S_0``; ``S_{j+1} = S_j ∪ {n ± g}`` for every
        generator ``g``; stop after ``order`` steps. Keep ``|n| <= max_harmonic``.

        Parameters
        ----------
        system
            Anything with ``load_harmonics`` and ``coefficient_harmonics`` (a
            :class:`~rheolin.PeriodicSystem` or an assembled model).
        order
            Number of times the generators are applied (the coupling order kept).
        max_harmonic
            Frequency cut-off as a harmonic index (None: no cut-off).
        generators
            Harmonic steps; default: the system's nonzero coefficient harmonics.
        max_size
            Refuse (:class:`~rheolin.budget.MemoryBudgetError`) as soon as the set would hold
            more indices than this, before it is grown further (None: no limit).

        Examples
        --------
        Unbalance at ``±1`` with an asymmetric rotor (stiffness harmonics ``±2``):

        >>> import numpy as np, rheolin as rl
        >>> s = rl.PeriodicSystem(1.0, M={0: np.eye(2)}, K={0: np.eye(2), 2: 0.1 * np.eye(2)},
        ...                       f={1: np.ones(2)})
        >>> HarmonicSet.closure(s, order=2).indices
        array([-5, -3, -1,  1,  3,  5])
        """
        if isinstance(order, bool) or not isinstance(order, int | np.integer) or order < 0:
            raise ValueError(f"`order` must be a non-negative integer, got {order!r}")
        seeds = set(int(k) for k in system.load_harmonics)
        if not seeds:
            raise ValueError("closure needs at least one load harmonic; the system has no load")
        gens = (
            sorted({abs(int(g)) for g in generators if int(g) != 0})
            if generators is not None
            else sorted({abs(int(g)) for g in system.coefficient_harmonics})
        )
        cap = None if max_harmonic is None else int(max_harmonic)
        if cap is not None and cap < 0:
            raise ValueError(f"`max_harmonic` must be >= 0, got {max_harmonic!r}")
        current = {n for n in seeds if cap is None or abs(n) <= cap}
        frontier = set(current)
        for _ in range(int(order)):
            new = set()
            for n in frontier:
                for g in gens:
                    for m in (n + g, n - g):
                        if (cap is None or abs(m) <= cap) and m not in current:
                            new.add(m)
                if max_size is not None and len(current) + len(new) > max_size:
                    from ..budget import MemoryBudgetError

                    raise MemoryBudgetError(
                        f"the harmonic set grows beyond max_size={max_size} indices "
                        f"(order {order}, {len(gens)} generators)"
                    )
            if not new:
                break
            current |= new
            frontier = new
        if not current:
            raise ValueError("`max_harmonic` removes every load harmonic")
        dropped = sorted(n for n in seeds if n > 0 and cap is not None and n > cap)
        if dropped:
            kept = sum(1 for n in seeds if n >= 0) - len(dropped)
            warnings.warn(
                f"max_harmonic={cap} leaves out {len(dropped)} of {len(dropped) + kept} load "
                f"harmonics ({_listing(dropped)}): their response is not computed; a cut-off "
                f"of at least {dropped[-1]} keeps them",
                TruncationWarning,
                stacklevel=2,
            )
        return cls(current)

    @property
    def indices(self) -> np.ndarray:
        """Sorted int64 array of the harmonic indices."""
        return self._indices

    @property
    def nonnegative(self) -> np.ndarray:
        """The indices ``n >= 0`` (the half that is solved; the rest are conjugates)."""
        return self._indices[self._indices >= 0]

    def __len__(self) -> int:
        return int(self._indices.size)

    def __iter__(self):  # type: ignore[no-untyped-def]
        return iter(int(i) for i in self._indices)

    def __contains__(self, n: object) -> bool:
        return isinstance(n, int | np.integer) and bool(np.any(self._indices == n))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, HarmonicSet) and np.array_equal(self._indices, other._indices)

    def __hash__(self) -> int:
        return hash(self._indices.tobytes())

    def __repr__(self) -> str:
        idx = self._indices
        if idx.size <= 9:
            body = ", ".join(str(i) for i in idx)
        else:
            body = f"{idx[0]}, {idx[1]}, ..., {idx[-2]}, {idx[-1]}; {idx.size} indices"
        return f"HarmonicSet([{body}])"


def _listing(values: list[int], head: int = 6) -> str:
    """``"840, 1120, ..., 1680"``: a short listing of integers."""
    if len(values) <= head:
        return ", ".join(str(v) for v in values)
    return ", ".join(str(v) for v in values[: head - 1]) + f", ..., {values[-1]}"


def as_harmonic_set(harmonics: HarmonicSet | int | Iterable[int]) -> HarmonicSet:
    """Accept an int ``N`` (meaning ``-N..N``), an iterable of ints, or a HarmonicSet."""
    if isinstance(harmonics, HarmonicSet):
        return harmonics
    if isinstance(harmonics, bool):
        raise ValueError("`harmonics` must be an int N, an iterable of ints or a HarmonicSet")
    if isinstance(harmonics, int | np.integer):
        return HarmonicSet.full(int(harmonics))
    try:
        return HarmonicSet(harmonics)
    except TypeError:
        raise ValueError(
            "`harmonics` must be an int N, an iterable of ints or a HarmonicSet, "
            f"got {type(harmonics).__name__}"
        ) from None
