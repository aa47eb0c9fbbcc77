"""Per-harmonic sparse factors of ``A0(n)``, held while they fit a memory budget.

One symbolic analysis of the pencil's pattern (:mod:`rheolin.linalg.direct`) serves every
harmonic (and every speed with that pattern: analyses are cached by pattern). The factors of
the first ``capacity`` harmonics are kept once made; when the harmonics outnumber what fits
(``capacity = factor budget // bytes per factor``), the others are factorized again each
time they are needed and released at once (a fixed set, not LRU: sweeps visit the harmonics
cyclically, which LRU would turn into a miss every time).

The bytes per factor come from the backend's analysis, which for SuperLU and UMFPACK is a
guess until they have factorized: so, when the guessed factor fits the budget, the factor of
the lowest harmonic, which is held first anyway, is made before the capacity is set, and its
measured size (with a margin of :data:`FILL_MARGIN` for the fill of the other harmonics)
replaces the guess. A held factor that would take the held ones past the budget all the same
is not held (it is refactorized on demand).
"""

from __future__ import annotations

import logging
import threading
from collections import OrderedDict
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .direct import Analysis, Factor, analyze, resolve_backend
from .direct.superlu import SuperLUBackend, backward_error, probe_vector
from .errors import SingularBlockError
from .pencil import Pencil
from .pool import map_chunks

__all__ = ["FactorStore", "analysis_for"]

log = logging.getLogger(__name__)

#: A factor whose probe solve has a larger backward error than this is redone by SuperLU
#: (checked pivoting).
PROBE_RTOL = 1e-10
#: The held factors are counted at this multiple of the measured size of the first one: the
#: fill differs from one harmonic to another.
FILL_MARGIN = 1.5

_CACHE: OrderedDict[tuple[Any, ...], Analysis] = OrderedDict()
_CACHE_LOCK = threading.Lock()
_CACHE_SIZE = 4


def analysis_for(pencil: Pencil, backend: str, complex_values: bool, slots: int = 1) -> Analysis:
    """The analysis of the pencil's pattern by ``backend`` (cached by pattern and slots)."""
    name = resolve_backend(backend, (pencil.indptr, pencil.indices, pencil.n))
    key = (
        name,
        complex_values,
        slots,
        pencil.n,
        pencil.indices.size,
        hash(pencil.indices.tobytes()),
        hash(pencil.indptr.tobytes()),
    )
    with _CACHE_LOCK:
        hit = _CACHE.get(key)
        if hit is not None:
            _CACHE.move_to_end(key)
            return hit
    k0, d0, m0 = pencil.values
    s = 1j * pencil.w1 if complex_values else 0.0
    sample = k0 + s * d0 + s * s * m0
    an = analyze(name, pencil.indptr, pencil.indices, complex_values, slots=slots, sample=sample)
    with _CACHE_LOCK:
        _CACHE[key] = an
        while len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)
    return an


class FactorStore:
    """Factors of ``A0(n)`` for the harmonics ``ns`` (sparse pencils).

    Parameters
    ----------
    pencil
        The sparse time-averaged pencil.
    ns
        Harmonics ``n >= 0``.
    backend
        Sparse backend name or ``"auto"`` (:func:`rheolin.linalg.direct.resolve_backend`).
    budget
        Bytes the held factors may take (None: hold all).
    workers
        Threads for backends that release the GIL.
    """

    def __init__(
        self,
        pencil: Pencil,
        ns: np.ndarray,
        backend: str = "auto",
        budget: int | None = None,
        workers: int = 1,
    ) -> None:
        self.pencil, self.ns = pencil, np.asarray(ns)
        self.backend = resolve_backend(backend, (pencil.indptr, pencil.indices, pencil.n))
        complex_count = int(np.count_nonzero(self.ns))
        # PARDISO keeps every factor of a pattern in one handle: one slot per harmonic
        self._complex = (
            analysis_for(pencil, self.backend, True, max(1, complex_count))
            if complex_count
            else None
        )
        self._real = analysis_for(pencil, self.backend, False, 1) if 0 in self.ns else None
        per = self._complex.factor_bytes if self._complex is not None else 0
        self.workers = max(1, int(workers))
        self._factors: dict[int, Factor] = {}
        self._lock = threading.Lock()
        self.refactorizations = 0
        order = np.argsort(np.abs(self.ns), kind="stable")
        ranked = [int(i) for i in order if self.ns[i] != 0]
        if budget is not None and ranked and per <= budget:
            first = self._make(ranked[0])  # measured rather than guessed (see the module)
            self._factors[ranked[0]] = first
            per = min(per, int(FILL_MARGIN * first.nbytes))
        self.factor_bytes = per
        if budget is not None and 0 in self.ns:
            budget -= per  # the real factor of n = 0 is always held
        if budget is None or per * complex_count <= budget:
            capacity = complex_count
        else:  # keep room for the factors made on demand, one per worker
            capacity = int(max(0, budget // max(per, 1) - self.workers))
        self.capacity = capacity
        held = ranked[:capacity]
        self._held = set(held) | {i for i in range(self.ns.size) if self.ns[i] == 0}
        for i in set(self._factors) - self._held:  # measured, but not to be held
            self._factors.pop(i).release()
        # what the held factors of n != 0 may take, and take now
        self._room = None if budget is None else budget - self.workers * per * self.on_demand
        self._taken = sum(f.nbytes for f in self._factors.values())
        if self.on_demand:
            log.info(
                "holding %d of %d factors (%.3g MB each); the rest are refactorized on demand",
                capacity,
                complex_count,
                per / 1e6,
            )

    @property
    def on_demand(self) -> bool:
        """True when some harmonics are refactorized each time they are used."""
        return len(self._held) < self.ns.size

    @property
    def factors_alive(self) -> int:
        """Most factors alive at once: the held ones and one per worker on demand."""
        return self.capacity + (self.workers if self.on_demand else 0) + (0 in self.ns)

    @property
    def name(self) -> str:
        """Backend name."""
        return self.backend

    def _make(self, i: int) -> Factor:
        n = int(self.ns[i])
        an = self._real if n == 0 else self._complex
        assert an is not None
        k0, d0, m0 = self.pencil.values
        s = 1j * self.pencil.w1 * n
        data = k0.copy() if n == 0 else k0 + s * d0 + (s * s) * m0
        try:
            f = an.factor(data)
        except SingularBlockError as exc:
            raise SingularBlockError(n, exc.detail) from None
        if self.backend == "superlu":  # probed by splu_checked, and SuperLU is the fallback
            return f
        b = np.array(probe_vector(self.pencil.n))
        x = f.solve(b)
        if not backward_error(self.pencil.matrix(n), x, b) <= PROBE_RTOL:
            log.debug("A0(%d): %s factor inaccurate; SuperLU instead", n, self.backend)
            f.release()
            fallback = SuperLUBackend(self.pencil.indptr, self.pencil.indices, n != 0)
            try:
                f = fallback.factor(data)
            except SingularBlockError as exc:
                raise SingularBlockError(n, exc.detail) from None
        return f

    def use(self, i: int, fn: Callable[[Factor], None]) -> None:
        """Call ``fn`` with the factor of harmonic ``ns[i]`` (made, or remade, as needed)."""
        if i in self._held:
            with self._lock:
                f = self._factors.get(i)
            if f is None:
                f = self._make(i)
                with self._lock:
                    if i in self._factors:  # another thread made it meanwhile
                        f.release()
                        f = self._factors[i]
                    elif self._fits(i, f):
                        self._factors[i] = f
                    else:  # past the budget after all: refactorized from now on
                        self._held.discard(i)
                        self.capacity -= 1
                if i not in self._held:
                    self._on_demand(f, fn)
                    return
            fn(f)
            return
        self._on_demand(self._make(i), fn)

    def _on_demand(self, f: Factor, fn: Callable[[Factor], None]) -> None:
        """``fn(f)``, then release the factor ``f`` (made for this use only)."""
        self.refactorizations += 1
        try:
            fn(f)
        finally:
            f.release()

    def _fits(self, i: int, f: Factor) -> bool:
        """Whether holding ``f`` (of harmonic ``ns[i]``) keeps the held factors within the
        budget (the caller holds the lock)."""
        if self._room is None or self.ns[i] == 0:
            return True
        if self._taken + f.nbytes > self._room:
            return False
        self._taken += f.nbytes
        return True

    def each(self, idx: Sequence[int] | np.ndarray, fn: Callable[[int, Factor], None]) -> None:
        """``fn(i, factor_i)`` for every ``i`` in ``idx`` (threads when the backend allows)."""
        idx = [int(i) for i in idx]
        an = self._complex or self._real
        workers = self.workers if an is not None and an.releases_gil else 1

        def run(chunk: Sequence[int]) -> None:
            for j in chunk:
                i = idx[j]

                def call(f: Factor, i: int = i) -> None:
                    fn(i, f)

                self.use(i, call)

        map_chunks(run, len(idx), workers)

    def held_bytes(self) -> int:
        """Bytes of the factors held now."""
        with self._lock:
            return int(sum(f.nbytes for f in self._factors.values()))

    def release(self) -> None:
        """Free every held factor."""
        with self._lock:
            for f in self._factors.values():
                f.release()
            self._factors.clear()
