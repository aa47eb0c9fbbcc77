"""The verdicts of a stability map's speeds (:func:`~rheolin.stability.stability_map`): one
after the other, each continued from the previous speed where it is close, or in contiguous
blocks on worker processes."""

from __future__ import annotations

import functools
import pickle
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..floquet import FloquetResult, floquet
from ..floquet.result import guarded
from ..harmonics.sets import as_harmonic_set
from .standstill import STANDSTILL, standstill_verdict

__all__ = [
    "CONTINUED_STEP",
    "Verdicts",
    "blocks_of",
    "continued_verdicts",
    "in_parallel",
    "verdict_block",
]

#: A speed of a map continues the previous speed's lattice searches only when it is at most
#: this fraction above it: farther, the copies of the exponents at the mesh harmonics have
#: moved past their neighbours and the tracked representatives are other copies, which a
#: finer lattice then cannot settle (docs/stability.md, section 5).
CONTINUED_STEP = 0.02

#: Seconds between looks at the workers' progress events while a map's blocks run.
EVENT_POLL = 0.2


@dataclass(frozen=True)
class Verdicts:
    """What the verdicts of a map's speeds are computed with (a worker's task: picklable
    unless ``harmonics`` is a callable)."""

    model: Any
    speeds: np.ndarray
    harmonics: Any = None
    method: str = "auto"
    order: int | None = None
    memory_budget: Any = None
    rtol: float | None = None
    key: str = ""  # a map's tasks share their model's speed template in a worker
    offset: int = 0  # the map's index of the first of ``speeds`` (a block on a worker)
    events: bool = False  # each verdict reported as a Dask event (someone is listening)
    reduce: Any = None  # a Craig-Bampton cut-off [rad/s] (True: the default) for every speed

    def evaluator(self) -> Callable[..., tuple[Any, FloquetResult]]:
        """``evaluate(W, continuation, accuracy, lattice_order)``: the model assembled at
        ``W`` (through its speed template) and its Floquet result."""
        template: Callable[[], Any] = (
            functools.partial(_shared_template, self.key, self.model)
            if self.key
            else functools.cache(self.model.speed_template)
        )

        def truncation(system: Any) -> Any:
            if self.harmonics is None:
                return None
            if callable(self.harmonics):
                return as_harmonic_set(self.harmonics(system))
            return as_harmonic_set(self.harmonics)

        reduced: dict[str, Any] = {}  # the Craig-Bampton basis, made at the first speed

        def on_reduction(system: Any, **options: Any) -> FloquetResult:
            from ..floquet.reduced import default_cutoff, floquet_reduced
            from ..system.reduction import craig_bampton

            if "basis" not in reduced:
                cut = default_cutoff(system) if self.reduce is True else float(self.reduce)
                reduced["basis"] = craig_bampton(system, cut)
            # a speed that needed a higher cut-off hands its basis on to the next
            return floquet_reduced(
                system,
                reduction=reduced["basis"],
                used=reduced,
                memory_budget=self.memory_budget,
                **options,
            )

        def evaluate(
            W: float,
            continuation: Any = None,
            accuracy: float | None = self.rtol,
            lattice_order: int | None = None,
        ) -> tuple[Any, FloquetResult]:
            # assembled once, rescaled at every speed (the same system as
            # ``model.assemble``, a fifteenth of its cost on the gearbox)
            a = template().assemble(float(W))
            if self.reduce is not None and self.reduce is not False:
                order = lattice_order if lattice_order is not None else self.order
                res = on_reduction(a.system, order=order, continuation=continuation, rtol=accuracy)
                return a, res
            if lattice_order is not None:
                res = floquet(
                    a.system,
                    method="lattice",
                    order=lattice_order,
                    memory_budget=self.memory_budget,
                    continuation=continuation,
                    rtol=accuracy,
                )
                return a, res
            res = floquet(
                a.system,
                truncation(a.system),
                method=self.method,
                order=self.order,
                memory_budget=self.memory_budget,
                continuation=continuation,
                rtol=accuracy,
            )
            return a, res

        return evaluate


def continued_verdicts(
    task: Verdicts,
    evaluate: Callable[..., tuple[Any, FloquetResult]],
    progress: Callable[[int, FloquetResult], None] | None = None,
) -> tuple[list[FloquetResult], int]:
    """The verdict at each of ``task.speeds`` in turn, each continued from the previous one
    when it is at most :data:`CONTINUED_STEP` above it; the results and how many were
    continued."""
    from ..floquet import Continuation

    speeds = task.speeds
    cont = Continuation()  # each speed's lattice searches start from the previous speed's
    results: list[FloquetResult] = []

    def at(W: float) -> FloquetResult:
        if W == 0:  # nothing turns: the frozen time-invariant system, exact
            return standstill_verdict(task.model, STANDSTILL, memory_budget=task.memory_budget)
        return evaluate(W, continuation=cont)[1]

    continued = 0
    for i, W in enumerate(speeds):
        if i and W - speeds[i - 1] > CONTINUED_STEP * W:
            cont.clear()  # too far from the previous speed: a verdict from scratch
        else:
            continued += int(i > 0)
        results.append(guarded(at, W))
        if results[-1].method == "failed":  # this speed undecided, with the reason
            cont.clear()
        if progress is not None:
            progress(i, results[-1])
    return results, continued


#: Speed templates of the maps a worker process has seen, by the map's key (the last few).
_TEMPLATES: dict[str, Any] = {}


def _shared_template(key: str, model: Any) -> Any:
    """The speed template of the map ``key`` in this process, assembled once."""
    if key not in _TEMPLATES:
        while len(_TEMPLATES) >= 2:
            _TEMPLATES.pop(next(iter(_TEMPLATES)))
        _TEMPLATES[key] = model.speed_template()
    return _TEMPLATES[key]


def blocks_of(speeds: np.ndarray, count: int) -> list[np.ndarray]:
    """The indices of ``speeds`` in contiguous blocks for ``count`` worker slots: the runs
    a map continues from speed to speed (steps of at most :data:`CONTINUED_STEP`) apart,
    the longest split in halves until there are ``count`` blocks or every block is one
    speed.

    >>> rpm = np.array([100.0, 101, 102, 103, 200, 300, 301])
    >>> [b.tolist() for b in blocks_of(rpm, 4)]
    [[0, 1], [2, 3], [4], [5, 6]]
    """
    if speeds.size == 0:
        return []
    wide = np.flatnonzero(np.diff(speeds) > CONTINUED_STEP * speeds[1:]) + 1
    blocks = [b for b in np.split(np.arange(speeds.size), wide) if b.size]
    while len(blocks) < count:
        longest = max(range(len(blocks)), key=lambda i: blocks[i].size)
        b = blocks[longest]
        if b.size < 2:
            break
        blocks[longest : longest + 1] = [b[: b.size // 2], b[b.size // 2 :]]
    return blocks


def verdict_block(task: Verdicts) -> tuple[list[FloquetResult], int]:
    """A worker's task: the verdicts of one block of a map's speeds (:func:`continued_verdicts`),
    each reported as it ends on the map's event topic (:func:`_topic`) when on a Dask worker."""
    return continued_verdicts(task, task.evaluator(), _reporter(task))


def _topic(key: str) -> str:
    return f"rheolin-map-{key}"


def _reporter(task: Verdicts) -> Callable[[int, FloquetResult], None] | None:
    """``report(i, result)`` as an event of the worker this runs on (the map's key, index and
    the pickled result: Dask's events travel as msgpack), on a forked worker's queue
    (:func:`~rheolin.study.executor.worker_events`) or as a Dask event; None outside a worker
    or when no one listens."""
    if not task.events:
        return None
    from ..study.executor import worker_events

    queue = worker_events()
    if queue is not None:

        def put(i: int, res: FloquetResult) -> None:
            queue.put({"key": task.key, "index": task.offset + i, "result": pickle.dumps(res)})

        return put
    try:
        from distributed import get_worker

        worker = get_worker()
    except (ImportError, ValueError):  # no Dask, or not on a worker
        return None
    topic = _topic(task.key)

    def report(i: int, res: FloquetResult) -> None:
        worker.log_event(topic, {"index": task.offset + i, "result": pickle.dumps(res)})

    return report


def in_parallel(
    task: Verdicts,
    workers: int | None,
    client: Any,
    progress: Callable[[int, FloquetResult], None] | None,
) -> tuple[list[FloquetResult], int]:
    """The verdicts of ``task.speeds`` in contiguous blocks on worker processes; ``progress``
    is called for each speed as its verdict ends (the workers' events), else, where an event
    is late, as its block ends."""
    import contextlib
    import queue
    import uuid
    from dataclasses import replace

    from ..budget import memory_budget as default_budget
    from ..study.executor import DaskExecutor, ForkExecutor, local_workers

    speeds = task.speeds
    if client is not None and not isinstance(client, (ForkExecutor, DaskExecutor)):
        client = DaskExecutor(client)  # a distributed.Client
    n = client.workers if client is not None else int(workers) if workers is not None else 1
    blocks = blocks_of(speeds, 2 * n)
    share = default_budget(task.memory_budget) // max(min(n, len(blocks)), 1)
    key = uuid.uuid4().hex
    results: list[FloquetResult | None] = [None] * speeds.size
    continued = 0
    reported: set[int] = set()
    events: Any = queue.SimpleQueue()

    def report(i: int, res: FloquetResult) -> None:
        if progress is not None and i not in reported:
            reported.add(i)
            progress(i, res)

    def drain() -> None:
        while True:
            try:
                msg = events.get_nowait()
            except queue.Empty:
                return
            report(int(msg["index"]), pickle.loads(msg["result"]))

    context = contextlib.nullcontext(client) if client is not None else local_workers(n)
    with context as ex:
        if isinstance(ex, DaskExecutor) and progress is not None:
            # events arrive on the client's thread: queued for this one
            ex.client.subscribe_topic(_topic(key), lambda event: events.put(event[1]))
        elif isinstance(ex, ForkExecutor):
            events = _Forwarded(ex.events, key)
        try:
            running = {}
            for b in blocks:
                part = replace(task, speeds=speeds[b], memory_budget=share, key=key,
                               offset=int(b[0]), events=progress is not None)  # fmt: skip
                running[ex.submit(verdict_block, part)] = b
            while running:
                while not ex.ready(timeout=EVENT_POLL):
                    drain()
                drain()
                handle, out, error = ex.next_done()
                b = running.pop(handle)
                if error is not None:
                    ex.cancel()
                    raise error
                found, k = out
                continued += k
                for i, res in zip(b, found, strict=True):
                    results[int(i)] = res
                    report(int(i), res)
        finally:
            if isinstance(ex, DaskExecutor) and progress is not None:
                with contextlib.suppress(Exception):
                    ex.client.unsubscribe_topic(_topic(key))
    return [r for r in results if r is not None], continued


class _Forwarded:
    """A forked pool's event queue read as the map's own (``get_nowait``): the events of
    this map's key; others (an earlier map's late reports) are dropped."""

    def __init__(self, source: Any, key: str) -> None:
        self.source, self.key = source, key

    def get_nowait(self) -> Any:
        import queue

        while not self.source.empty():
            msg = self.source.get()
            if msg.get("key") == self.key:
                return msg
        raise queue.Empty
