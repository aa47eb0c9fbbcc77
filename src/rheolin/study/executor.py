"""Where tasks run: in this process (serial), on a Dask cluster (``dask.distributed``), or
on copies of this process (:class:`ForkExecutor`, for the short maps of a command).

The executors offer the same three calls (``submit``, ``next_done``, ``cancel``), so a study
has one code path. :func:`local_cluster` starts the default cluster: processes with one
thread each (the solvers hold the GIL in SuperLU), one BLAS thread per worker.
:func:`local_workers` gives forked workers where this process can be forked safely (the
workers start in milliseconds with everything this process has imported: a stability map
of a few seconds a speed does not wait for a cluster), else a local cluster.

:class:`Planner` cuts the points still to do into chunks: the first tasks have one point each,
then chunks aim at :data:`TARGET_SECONDS` from the measured time per point, so progress and
checkpoints stay frequent for slow models and the per-task overhead small for fast ones. The
chunking never changes a result: every point is solved on its own.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import logging
import multiprocessing
import os
import signal
import threading
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from typing import Any

__all__ = [
    "BLAS_ENV",
    "TARGET_SECONDS",
    "DaskExecutor",
    "ForkExecutor",
    "Planner",
    "SerialExecutor",
    "cores",
    "local_cluster",
    "local_workers",
    "worker_events",
]

#: Environment of every worker process: one BLAS/OpenMP thread.
BLAS_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
#: Aimed duration of one chunk [s].
TARGET_SECONDS = 5.0
#: Most points in one chunk.
MAX_CHUNK = 256


class Planner:
    """Chunks of the pending points; a chunk never mixes parameter combinations, and never
    splits a continuation block (``block_of``: the points solved as one sequence).

    >>> p = Planner([0, 1, 2, 3, 7, 8], combo_of=lambda i: i // 5, slots=1)
    >>> p.next(), p.observe(1, 0.5), p.next(), p.next()
    ([0], None, [1, 2, 3], [7, 8])
    >>> Planner(range(6), combo_of=lambda i: 0, chunk_size=1, block_of=lambda i: i // 4).next()
    [0, 1, 2, 3]
    """

    def __init__(
        self,
        points: Sequence[int],
        combo_of: Callable[[int], int],
        *,
        slots: int = 1,
        chunk_size: int | None = None,
        block_of: Callable[[int], Any] | None = None,
    ) -> None:
        self.pending = deque(sorted(points))
        self.combo_of = combo_of
        self.block_of = block_of
        self.fixed = chunk_size
        self.seconds_per_point: float | None = None
        self.slots = max(1, slots)

    def __bool__(self) -> bool:
        return bool(self.pending)

    def observe(self, points: int, seconds: float) -> None:
        """Measured time of a finished chunk (running mean per point)."""
        if points > 0:
            rate = seconds / points
            old = self.seconds_per_point
            self.seconds_per_point = rate if old is None else 0.7 * old + 0.3 * rate

    def next(self) -> list[int]:
        """The next chunk (empty when nothing is pending)."""
        size = self.fixed or self._size()
        if not self.pending:
            return []
        combo = self.combo_of(self.pending[0])
        out = [self.pending.popleft()]
        while self.pending and self.combo_of(self.pending[0]) == combo:
            whole = self.block_of is not None and (
                self.block_of(self.pending[0]) == self.block_of(out[-1])
            )
            if len(out) >= size and not whole:
                break
            out.append(self.pending.popleft())
        return out

    def _size(self) -> int:
        if self.seconds_per_point is None:
            return 1
        size = int(TARGET_SECONDS / max(self.seconds_per_point, 1e-6))
        share = -(-len(self.pending) // self.slots)  # keep every slot busy to the end
        return max(1, min(size, share, MAX_CHUNK))


class SerialExecutor:
    """Runs each task in this process when its result is asked for."""

    slots = 1

    def __init__(self) -> None:
        self._queue: deque[tuple[int, Callable[[Any], Any], Any]] = deque()
        self._count = 0

    def submit(self, fn: Callable[[Any], Any], task: Any) -> int:
        self._count += 1
        self._queue.append((self._count, fn, task))
        return self._count

    def next_done(self) -> tuple[int, Any, BaseException | None]:
        handle, fn, task = self._queue.popleft()
        try:
            return handle, fn(task), None
        except Exception as exc:
            return handle, None, exc

    def cancel(self) -> None:
        self._queue.clear()


class DaskExecutor:
    """Tasks as futures on a ``distributed.Client``; results in completion order."""

    def __init__(self, client: Any) -> None:
        from distributed import as_completed

        self.client = client
        self.workers = max(1, sum(client.nthreads().values()))  # worker threads
        self.slots = 2 * self.workers
        self._done = as_completed()
        self._futures: dict[Any, Any] = {}

    def submit(self, fn: Callable[[Any], Any], task: Any) -> Any:
        future = self.client.submit(fn, task, pure=False)
        self._futures[future.key] = future
        self._done.add(future)
        return future.key

    def ready(self, timeout: float) -> bool:
        """Whether a task has ended (waiting up to ``timeout`` seconds for one)."""
        from distributed import wait

        if self._done.has_ready() or not self._futures:
            return True
        with contextlib.suppress(TimeoutError):
            wait(list(self._futures.values()), timeout=timeout, return_when="FIRST_COMPLETED")
        return self._done.has_ready()

    def next_done(self) -> tuple[Any, Any, BaseException | None]:
        future = next(self._done)
        self._futures.pop(future.key, None)
        try:
            return future.key, future.result(), None
        except Exception as exc:  # the task raised, or its worker died (KilledWorker)
            return future.key, None, exc

    def cancel(self) -> None:
        if self._futures:
            with contextlib.suppress(Exception):
                self.client.cancel(list(self._futures.values()))
        self._futures.clear()


@contextlib.contextmanager
def local_cluster(workers: int | None = None) -> Iterator[Any]:
    """A ``distributed.Client`` on a new ``LocalCluster`` of ``workers`` processes (default:
    the cores available), one thread and one BLAS thread each; closed on exit."""
    import dask
    from distributed import Client, LocalCluster

    n = workers or cores()
    spawn_env = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {}))
    # any fixed MALLOC_TRIM_THRESHOLD_ (Dask sets 64 KiB) turns off glibc's adaptive mmap
    # threshold, so every medium-sized array of the lattice search would be mapped and
    # unmapped again: the workers keep glibc's defaults
    spawn_env.pop("MALLOC_TRIM_THRESHOLD_", None)
    settings = {
        "distributed.nanny.pre-spawn-environ": {**spawn_env, **BLAS_ENV},
        # without a dashboard nothing reads the profiler or the monitors, tasks are submitted
        # when a worker is free (no stealing) and rheolin budgets its own memory: idle
        # workers and the client poll rarely
        "distributed.worker.profile.enabled": False,
        "distributed.scheduler.work-stealing": False,
        "distributed.admin.tick.interval": "1s",
        "distributed.admin.system-monitor.interval": "10s",
        "distributed.worker.memory.monitor-interval": "1s",
    }
    with dask.config.set(settings), _sigint_ignored():
        cluster = LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            # task failures come back through their futures; what the cluster logs at ERROR
            # is shutdown noise (a tornado callback interrupted by Ctrl-C) on the user's console
            silence_logs=logging.CRITICAL,
        )
    client = Client(cluster)
    try:
        yield client
    finally:
        with _quiet("tornado", "distributed", "asyncio"):
            with contextlib.suppress(Exception):
                client.close()
            with contextlib.suppress(Exception):
                cluster.close()


#: In a :class:`ForkExecutor`'s worker: the queue its tasks report events on (None elsewhere).
_EVENTS: Any = None


def worker_events() -> Any:
    """The event queue of the :class:`ForkExecutor` this process is a worker of, or None."""
    return _EVENTS


def _fork_worker(events: Any) -> None:
    """A forked worker's start: one BLAS thread (the environment is read when a BLAS library
    loads, which happened in the parent), Ctrl-C left to the parent (which ends the pool),
    SIGTERM back to its default (the parent's handler, a command's
    :func:`~rheolin.cli.errors.sigterm_as_interrupt`, is copied by the fork: the pool's
    ``close`` would make each worker print a KeyboardInterrupt traceback) and the pool's
    event queue."""
    global _EVENTS
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _EVENTS = events


def _started() -> int:
    return os.getpid()


class ForkExecutor:
    """Tasks on ``workers`` forked copies of this process (``concurrent.futures``); results
    in completion order. The workers are forked when it is made, so it must be made before
    this process starts any other thread (a fork copies only the calling thread, and a lock
    another thread held would stay locked in the copy): :func:`fork_safe`. ``events``: a
    queue the workers' tasks may report on (:func:`worker_events`)."""

    def __init__(self, workers: int) -> None:
        ctx = multiprocessing.get_context("fork")
        self.workers = max(1, int(workers))
        self.slots = 2 * self.workers
        self.events = ctx.SimpleQueue()
        self._pool = cf.ProcessPoolExecutor(
            self.workers, mp_context=ctx, initializer=_fork_worker, initargs=(self.events,)
        )
        # with the fork start method every worker is started at the first submit
        self._pool.submit(_started).result()
        self._futures: dict[int, cf.Future[Any]] = {}
        self._count = 0

    def submit(self, fn: Callable[[Any], Any], task: Any) -> int:
        self._count += 1
        self._futures[self._count] = self._pool.submit(fn, task)
        return self._count

    def ready(self, timeout: float) -> bool:
        """Whether a task has ended (waiting up to ``timeout`` seconds for one)."""
        if not self._futures:
            return True
        done, _ = cf.wait(self._futures.values(), timeout=timeout, return_when=cf.FIRST_COMPLETED)
        return bool(done)

    def next_done(self) -> tuple[int, Any, BaseException | None]:
        cf.wait(self._futures.values(), return_when=cf.FIRST_COMPLETED)
        handle = next(h for h, f in self._futures.items() if f.done())
        future = self._futures.pop(handle)
        try:
            return handle, future.result(), None
        except Exception as exc:  # the task raised, or a worker died (BrokenProcessPool)
            return handle, None, exc

    def cancel(self) -> None:
        for f in self._futures.values():
            f.cancel()
        self._futures.clear()

    def close(self) -> None:
        """Ends the workers, those still running a task included."""
        running = any(not f.done() for f in self._futures.values())
        self.cancel()
        if running:
            # a running task is not cancelled by the pool: its worker is ended (Ctrl-C, or
            # an error in another task), not waited for
            for proc in list(getattr(self._pool, "_processes", {}).values()):
                with contextlib.suppress(Exception):
                    proc.terminate()
        self._pool.shutdown(wait=True, cancel_futures=True)


def fork_safe() -> bool:
    """Whether this process may be forked for workers now: the platform forks (not Windows,
    not macOS, whose system libraries are not fork-safe) and this is its only thread."""
    import sys

    return (
        sys.platform.startswith("linux")
        and "fork" in multiprocessing.get_all_start_methods()
        and threading.active_count() == 1
    )


@contextlib.contextmanager
def local_workers(workers: int | None = None) -> Iterator[Any]:
    """An executor on ``workers`` local processes (default: the cores available): a
    :class:`ForkExecutor` where :func:`fork_safe`, else a :class:`DaskExecutor` on a
    :func:`local_cluster`; ended on exit."""
    n = workers or cores()
    if fork_safe():
        ex = ForkExecutor(n)
        try:
            yield ex
        finally:
            ex.close()
        return
    with local_cluster(n) as client:
        yield DaskExecutor(client)


@contextlib.contextmanager
def _quiet(*names: str) -> Iterator[None]:
    """Loggers ``names`` at CRITICAL while closing the cluster (an interrupted close logs
    tracebacks of cancelled callbacks that are not errors of the study)."""
    loggers = [logging.getLogger(n) for n in names]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for lg, level in zip(loggers, levels, strict=True):
            lg.setLevel(level)


@contextlib.contextmanager
def _sigint_ignored() -> Iterator[None]:
    """Worker processes started inside inherit an ignored SIGINT: Ctrl-C in a terminal
    (sent to the whole process group) reaches only this process, which stops the study."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def cores() -> int:
    """Cores available to this process."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - non-Linux
        return os.cpu_count() or 1
