"""What runs on a worker: a chunk of points, or the stability map of one combination.

Both are plain functions of picklable tasks, so the same code runs in the calling process
(serial) and on Dask workers. Each runs with one BLAS thread and the study's memory budget
(``RHEOLIN_MEMORY_BUDGET``, fixed when the study was created): the Floquet method chosen
within the budget, and so every result, is the same whatever the workers and the memory free
at the time.
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
import warnings
from collections import OrderedDict
from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import xarray as xr
from threadpoolctl import threadpool_limits

from ..budget import MemoryBudgetError
from ..harmonics.sets import TruncationWarning
from ..io.loader import LoadedModel
from .chunks import chunk_dataset, point_row
from .spec import Settings, StudySpec

__all__ = ["ChunkResult", "ChunkTask", "MapTask", "compute_chunk", "compute_map", "describe_error"]


@dataclass
class ChunkTask:
    """Points of one parameter combination (consecutive speeds, usually)."""

    spec: StudySpec
    combo: int
    points: list[int]
    budget: int


@dataclass
class ChunkResult:
    """The computed points (None if none), the points that raised, warnings, timing."""

    points: list[int]
    dataset: xr.Dataset | None
    failures: dict[int, str] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    seconds: float = 0.0
    worker: int = 0


@dataclass
class MapTask:
    """Refine the unstable ranges of one combination (:func:`map_from_results`)."""

    spec: StudySpec
    combo: int
    speeds: list[float]
    results: list[Any]
    refine: float
    budget: int


def compute_chunk(task: ChunkTask) -> ChunkResult:
    """Solve every point of the chunk; a point that raises is reported, not fatal."""
    t0 = time.perf_counter()
    spec, s = task.spec, task.spec.settings
    rows, done, failures, notes = [], [], {}, []
    with _limits(task.budget):
        try:
            lm = _model(spec, task.combo)
        except Exception as exc:  # a combination the model file refuses
            msg = describe_error(exc)
            return ChunkResult(task.points, None, dict.fromkeys(task.points, msg), [], 0.0)
        order = lm.spec.harmonics.order if s.order is None else s.order
        max_order = lm.spec.harmonics.max_order if s.max_order is None else s.max_order
        template = _template(spec, task.combo, lm)
        chain = _Chain(spec)
        for point in task.points:
            speed = float(spec.speeds[spec.speed_of(point)])
            t = time.perf_counter()
            x0, cont = chain.start(point)
            try:
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always", TruncationWarning)
                    row, sol = _solve(lm, speed, s, order, max_order, t, template, x0, cont)
                    rows.append(row)
                chain.done(point, sol)
                done.append(point)
                for w in caught:
                    if issubclass(w.category, TruncationWarning) and str(w.message) not in notes:
                        notes.append(str(w.message))
            except Exception as exc:
                failures[point] = describe_error(exc)
    ds = chunk_dataset(done, rows, spec.key) if rows else None
    return ChunkResult(
        task.points, ds, failures, notes, time.perf_counter() - t0, worker=os.getpid()
    )


#: A point of a continuation block starts from the polynomial extrapolation of up to this
#: many previous speeds' solutions (each further one saved gmres iterations on the gearbox).
EXTRAPOLATION_POINTS = 4


class _Chain:
    """The continuation within a block: a point starts from its predecessors' solutions and
    Floquet eigenvectors when they are the previous speeds of the same block, solved just
    before in this task (so always, unless one failed). The start is the polynomial
    extrapolation of up to :data:`EXTRAPOLATION_POINTS` predecessors to the new speed (only an
    initial guess: the solve's own convergence test decides)."""

    def __init__(self, spec: StudySpec) -> None:
        from ..floquet import Continuation

        self.spec = spec
        self.last: int | None = None
        self.history: list[tuple[float, Any]] = []  # (speed, solution), the last few
        self.continuation = Continuation(rtol=spec.settings.floquet_rtol)

    def start(self, point: int) -> tuple[Any, Any]:
        """``(x0, continuation)`` for ``point``."""
        spec = self.spec
        linked = (
            self.last is not None
            and point == self.last + 1
            and spec.block_of(point) == spec.block_of(self.last)
        )
        if not linked:
            self.history.clear()
            self.continuation.clear()
        self.last = None  # until this point is done
        if not self.history:
            return None, self.continuation
        w = float(spec.speeds[spec.speed_of(point)])
        last = self.history[-1][1]
        same = [
            (wi, si)
            for wi, si in self.history
            if np.array_equal(si.harmonics, last.harmonics) and si.q.shape == last.q.shape
        ]
        ws = np.array([wi for wi, _ in same])
        if len(same) < 2 or np.unique(ws).size != ws.size:
            return last, self.continuation
        q = np.zeros_like(last.q)
        for j, (wj, sj) in enumerate(same):  # Lagrange weights at the new speed
            others = np.delete(ws, j)
            q = q + sj.q * float(np.prod((w - others) / (wj - others)))
        return replace(last, q=q), self.continuation

    def done(self, point: int, solution: Any) -> None:
        self.last = point
        if not np.all(np.isfinite(solution.q)):
            self.history.clear()
            return
        w = float(self.spec.speeds[self.spec.speed_of(point)])
        keep = EXTRAPOLATION_POINTS - 1
        self.history = [*self.history[-keep:], (w, solution)]


def _solve(
    lm: LoadedModel,
    speed: float,
    s: Settings,
    order: int,
    max_order: float | None,
    t0: float,
    template: Any = None,
    x0: Any = None,
    continuation: Any = None,
) -> tuple[Any, Any]:
    """The point's row and its solution, from ``x0`` (the previous speed's solution, or
    None) with the Floquet ``continuation`` of its block."""
    from ..floquet import floquet
    from ..floquet.result import guarded
    from ..results.compute import solve_point

    p = solve_point(
        lm.model,
        speed,
        method=s.method,
        order=order,
        max_order=max_order,
        rtol=s.rtol,
        stability=s.stability,
        template=template,
        x0=x0,
        continuation=continuation,
    )
    result = p.solution.floquet
    if result is None and s.stability_map:
        try:  # for the map: the verdict is off, or skipped by the budget check
            result = guarded(floquet, p.assembled.system, continuation=continuation)
        except MemoryBudgetError as exc:
            p.solution.message += f"; no Floquet result for the stability map: {exc}"
        if result is not None and result.method == "failed":  # the steady state stands
            p.solution.message += (
                f"; no Floquet result for the stability map: {result.info['error']}"
            )
    return point_row(p, result, time.perf_counter() - t0), p.solution


def compute_map(task: MapTask) -> Any:
    """The combination's :class:`~rheolin.stability.StabilityMap` with refined ranges."""
    from ..stability import map_from_results

    with _limits(task.budget):
        model = _model(task.spec, task.combo).model
        return map_from_results(model, task.speeds, task.results, refine=task.refine)


# ---------------------------------------------------------------------- helpers
_CACHE: OrderedDict[tuple[str, int], LoadedModel] = OrderedDict()
_TEMPLATES: dict[tuple[str, int], Any] = {}
_LOCK = threading.Lock()


def _template(spec: StudySpec, combo: int, lm: LoadedModel) -> Any:
    """The combination's speed template (the model assembled once), kept with the model."""
    key = (spec.key, combo)
    with _LOCK:
        if key in _TEMPLATES:
            return _TEMPLATES[key]
    template = lm.model.speed_template()
    with _LOCK:
        _TEMPLATES[key] = template
        for k in [k for k in _TEMPLATES if k not in _CACHE and k != key]:
            del _TEMPLATES[k]
    return template


def _model(spec: StudySpec, combo: int) -> LoadedModel:
    """The combination's model, built once per worker process (the last few kept)."""
    key = (spec.key, combo)
    with _LOCK:
        if key in _CACHE:
            _CACHE.move_to_end(key)
            return _CACHE[key]
    lm = spec.loaded(combo)
    with _LOCK:
        _CACHE[key] = lm
        while len(_CACHE) > 4:
            _CACHE.popitem(last=False)
    return lm


class _Pinned:
    """How many tasks of this process hold the budget, and the value to restore."""

    count = 0
    old: str | None = None


@contextlib.contextmanager
def _limits(budget: int) -> Iterator[None]:
    """One BLAS thread and ``RHEOLIN_MEMORY_BUDGET = budget`` while inside (tasks of one
    study running side by side in one process share the same value)."""
    name = "RHEOLIN_MEMORY_BUDGET"
    with _LOCK:
        if _Pinned.count == 0:
            _Pinned.old = os.environ.get(name)
        _Pinned.count += 1
        os.environ[name] = str(int(budget))
    try:
        with threadpool_limits(limits=1):
            yield
    finally:
        with _LOCK:
            _Pinned.count -= 1
            if _Pinned.count == 0:
                if _Pinned.old is None:
                    os.environ.pop(name, None)
                else:
                    os.environ[name] = _Pinned.old


def describe_error(exc: BaseException) -> str:
    """``"Type: message"`` on one line."""
    text = str(exc).strip().replace("\n", " ")
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__
