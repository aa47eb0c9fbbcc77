"""Run a study: the points still missing in chunks on an executor, checkpointed as they finish,
then the stability maps and the results.

>>> from rheolin.data import example_path
>>> spec = StudySpec.create(example_path("rotor"), [300.0, 400.0],
...                         settings=Settings(stability=False, stability_map=False))
>>> res = run_study(spec)
>>> res.dataset["response"].dims, res.dataset["success"].values.tolist()
(('speed', 'harmonic', 'node'), [1, 1])
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import xarray as xr

from ..budget import memory_budget
from .assemble import assemble, maps_dataset
from .chunks import floquet_results
from .executor import (
    DaskExecutor,
    ForkExecutor,
    Planner,
    SerialExecutor,
    cores,
    local_workers,
)
from .spec import Settings, StudySpec
from .store import CheckpointStore, MemoryStore
from .worker import (
    ChunkResult,
    ChunkTask,
    MapTask,
    compute_chunk,
    compute_map,
    describe_error,
)

__all__ = ["MAP_PRECISION", "StudyInterrupted", "StudyProgress", "StudyResult", "run_study"]

#: Relative precision of the unstable-range bounds (0.04 rpm at 4000 rpm).
MAP_PRECISION = 1e-5


@dataclass
class StudyProgress:
    """Passed to the ``progress`` callback after every finished task.

    ``done``/``total`` count points, then (phase ``"maps"``) stability maps being refined
    on top: ``total`` grows by their number when that phase starts. ``failures`` are the
    points (number, message) that failed in the last task.
    """

    phase: str
    done: int
    total: int
    resumed: int
    failed: int
    failures: list[tuple[int, str]] = field(default_factory=list)


@dataclass
class StudyResult:
    """What a study computed.

    Attributes
    ----------
    spec
        The study.
    dataset
        Results over ``(*parameters, speed)`` (``sweep.nc``).
    maps
        Stability map per parameter combination (:class:`~rheolin.stability.StabilityMap`).
    failures
        Points that raised in this run: ``{point: message}``.
    resumed, computed
        Points found in the checkpoint, points computed now.
    warnings
        Warnings of the solves (a truncated harmonic set), once each.
    written
        Files written (with an output directory).
    """

    spec: StudySpec
    dataset: xr.Dataset
    maps: dict[int, Any]
    failures: dict[int, str]
    resumed: int
    computed: int
    warnings: list[str]
    seconds: float
    written: list[Path] = field(default_factory=list)

    def stability_dataset(self) -> xr.Dataset | None:
        """The stability maps as one Dataset (``stability_map.nc``)."""
        return maps_dataset(self.spec, self.maps)

    def map(self, **values: float) -> Any:
        """The stability map at parameter values given by path, e.g.
        ``result.map(**{"bearings.input_A.stiffness": 2e8})``; no arguments without
        parameters."""
        index = []
        for p in self.spec.parameters:
            if p.path not in values:
                raise KeyError(f"give a value for {p.path!r}")
            index.append(p.values.index(values[p.path]))
        combo = 0
        for p, i in zip(self.spec.parameters, index, strict=True):
            combo = combo * len(p.values) + i
        return self.maps.get(combo)


class StudyInterrupted(KeyboardInterrupt):
    """Ctrl-C during a study: the finished chunks are kept (``done`` of ``total`` points)."""

    def __init__(self, done: int, total: int, directory: Path | None) -> None:
        super().__init__(f"interrupted with {done} of {total} points done")
        self.done, self.total, self.directory = done, total, directory


def run_study(
    spec: StudySpec,
    *,
    out: str | Path | None = None,
    overwrite: bool = False,
    client: Any = None,
    workers: int | None = 1,
    chunk_size: int | None = None,
    progress: Callable[[StudyProgress], None] | None = None,
    refine: float = MAP_PRECISION,
    write: Callable[[StudyResult, CheckpointStore], list[Path]] | None = None,
) -> StudyResult:
    """Compute every point of ``spec`` that is not yet in the checkpoint, then the stability
    maps (``spec.settings.stability_map``) and the results.

    Parameters
    ----------
    out
        Output directory: its ``checkpoint/`` keeps every finished chunk, and a re-run of the
        same study computes only the missing points (see :mod:`rheolin.study.store`).
        None: nothing is written.
    overwrite
        Discard another study's checkpoint and results in ``out`` instead of refusing.
    client
        A ``distributed.Client``: run on that cluster; or an executor of
        :mod:`rheolin.study.executor` (:func:`~rheolin.study.executor.local_workers`).
    workers
        Without ``client``: 1 runs in this process (no Dask), more start that many local
        worker processes for this study (at most one per missing point; forked copies of this
        process where that is safe, else a local Dask cluster), None as many as there are
        cores.
    chunk_size
        Points per task, rounded up to whole continuation blocks (default: adaptive, see
        :class:`~rheolin.study.executor.Planner`).
    progress
        Called with a :class:`StudyProgress` after every finished task.
    refine
        Relative precision of the unstable-range bounds.
    write
        Called as ``write(result, store)`` while the directory is still locked, to write the
        result files (:func:`rheolin.study.files.write_results`); default: that function with
        plots.

    Raises
    ------
    StudyInterrupted
        On Ctrl-C; the finished chunks stay in the checkpoint.
    rheolin.study.store.StudyConflict, rheolin.study.store.StudyBusy
        ``out`` holds another study, or another process is running one there.
    """
    t0 = time.perf_counter()
    store: MemoryStore = CheckpointStore(out) if out is not None else MemoryStore()
    try:
        if isinstance(store, CheckpointStore):
            budget = store.open(spec, budget=memory_budget(), overwrite=overwrite)
        else:
            budget = memory_budget()
        done = store.done() & set(range(spec.n_points))
        state = _State(spec, len(done), progress)
        pending = [p for p in range(spec.n_points) if p not in done]
        with _executor(client, workers, len(pending)) as ex:
            try:
                _points(spec, pending, ex, store, state, budget, chunk_size)
                chunks = store.read_all()
                maps = _maps(spec, chunks, ex, store, state, budget, refine)
            except KeyboardInterrupt:
                ex.cancel()
                directory = Path(out) if out is not None else None
                raise StudyInterrupted(state.done, spec.n_points, directory) from None
        ds = assemble(spec, chunks, state.failures, _settings(spec))
        result = StudyResult(
            spec,
            ds,
            maps,
            state.failures,
            state.resumed,
            state.computed,
            state.warnings,
            time.perf_counter() - t0,
        )
        if isinstance(store, CheckpointStore):
            from .files import write_results

            result.written = (write or write_results)(result, store)
        return result
    finally:
        if isinstance(store, CheckpointStore):
            store.close()


class _State:
    def __init__(self, spec: StudySpec, resumed: int, progress: Any) -> None:
        self.total = spec.n_points
        self.done = self.resumed = resumed
        self.computed = 0
        self.failures: dict[int, str] = {}
        self.warnings: list[str] = []
        self.progress = progress
        self.phase = "points"

    def report(self, failures: list[tuple[int, str]] = ()) -> None:  # type: ignore[assignment]
        if self.progress is not None:
            self.progress(
                StudyProgress(
                    self.phase,
                    self.done,
                    self.total,
                    self.resumed,
                    len(self.failures),
                    list(failures),
                )
            )


@contextlib.contextmanager
def _executor(client: Any, workers: int | None, pending: int) -> Iterator[Any]:
    n = min(cores() if workers is None else workers, pending)
    if isinstance(client, (DaskExecutor, ForkExecutor)):
        yield client
    elif client is not None:
        yield DaskExecutor(client)
    elif n > 1:
        with local_workers(n) as ex:
            yield ex
    else:
        yield SerialExecutor()


def _points(
    spec: StudySpec,
    pending: list[int],
    ex: Any,
    store: MemoryStore,
    state: _State,
    budget: int,
    chunk_size: int | None,
) -> None:
    planner = Planner(
        pending, spec.combo_of, slots=ex.slots, chunk_size=chunk_size, block_of=spec.block_of
    )
    state.report()
    running: dict[Any, list[int]] = {}
    while planner or running:
        while planner and len(running) < ex.slots:
            points = planner.next()
            task = ChunkTask(spec, spec.combo_of(points[0]), points, budget)
            running[ex.submit(compute_chunk, task)] = points
        handle, result, error = ex.next_done()
        points = running.pop(handle)
        if error is not None:  # the task itself failed (e.g. its worker died)
            result = ChunkResult(points, None, dict.fromkeys(points, describe_error(error)))
        if result.dataset is not None:
            store.write(result.dataset)
        new = sorted(result.failures.items())
        state.failures.update(new)
        for w in result.warnings:
            if w not in state.warnings:
                state.warnings.append(w)
        planner.observe(len(points), result.seconds)
        state.done += len(points)
        state.computed += len(points) - len(new)
        state.report(new)


def _maps(
    spec: StudySpec,
    chunks: list[xr.Dataset],
    ex: Any,
    store: MemoryStore,
    state: _State,
    budget: int,
    refine: float,
) -> dict[int, Any]:
    """Stability map per combination: cached, built here when every speed is stable (nothing
    to refine), else refined by a task."""
    from ..stability import map_from_results

    if not spec.settings.stability_map:
        return {}
    results: dict[int, Any] = {}
    for c in chunks:
        results.update(floquet_results(c))
    ns = spec.speeds.size
    maps: dict[int, Any] = {}
    tasks = []
    for combo in range(spec.n_combos):
        have = [p for p in range(combo * ns, (combo + 1) * ns) if p in results]
        if not have:
            continue
        complete = len(have) == ns
        cached = store.load_map(combo, refine) if complete else None
        if cached is not None:
            maps[combo] = cached
            continue
        speeds = [float(spec.speeds[spec.speed_of(p)]) for p in have]
        found = [results[p] for p in have]
        if all(r.stable for r in found):  # no range: the model is not needed
            maps[combo] = map_from_results(None, speeds, found, refine=refine)
            if complete:
                store.save_map(combo, refine, maps[combo])
        else:
            tasks.append((combo, complete, MapTask(spec, combo, speeds, found, refine, budget)))
    if not tasks:
        return maps
    state.phase = "maps"
    state.total += len(tasks)
    state.report()
    running = {ex.submit(compute_map, t): (combo, complete) for combo, complete, t in tasks}
    while running:
        handle, smap, error = ex.next_done()
        combo, complete = running.pop(handle)
        state.done += 1
        if error is not None:
            message = (
                f"stability map of {spec.describe(combo) or 'the sweep'}: {describe_error(error)}"
            )
            state.warnings.append(message)
        else:
            maps[combo] = smap
            if complete:
                store.save_map(combo, refine, smap)
        state.report()
    return maps


def _settings(spec: StudySpec) -> dict[str, Any]:
    """Method and harmonic settings for the attributes (the file's when not overridden)."""
    s: Settings = spec.settings
    h = spec.document.get("harmonics", {})
    order = s.order if s.order is not None else h.get("order", 2)
    max_order = s.max_order if s.max_order is not None else h.get("max_order")
    return {"method": s.method, "order": order, "max_order": max_order}
