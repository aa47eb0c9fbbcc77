"""One long-lived thread pool per size, shared by every solve (or none).

A new ``ThreadPoolExecutor`` per factorization costs thread start-up each time, and SciPy's
SuperLU called from fresh threads grows the resident memory (each new thread gets its own
malloc arena). The pool here is made once and kept until exit. SuperLU holds the GIL while
factorizing, so threads do not speed it up and the default is no pool at all:
``default_workers() == 1``.
"""

from __future__ import annotations

import atexit
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor

__all__ = ["default_workers", "map_chunks", "shared_pool"]

_POOLS: dict[int, ThreadPoolExecutor] = {}
_LOCK = threading.Lock()


def default_workers() -> int:
    """Threads for per-harmonic work when the caller gives none: 1 (serial; see the module)."""
    return 1


def _shutdown() -> None:
    with _LOCK:
        for pool in _POOLS.values():
            pool.shutdown(wait=False)
        _POOLS.clear()


atexit.register(_shutdown)


def shared_pool(workers: int) -> ThreadPoolExecutor | None:
    """The process-wide pool of ``workers`` threads (made on first use), or None for 1.

    >>> shared_pool(1) is None, shared_pool(2) is shared_pool(2)
    (True, True)
    """
    if workers <= 1:
        return None
    with _LOCK:
        pool = _POOLS.get(workers)
        if pool is None:
            pool = ThreadPoolExecutor(workers, thread_name_prefix=f"rheolin-{workers}")
            _POOLS[workers] = pool
        return pool


def map_chunks(run: Callable[[Sequence[int]], None], count: int, workers: int) -> None:
    """Call ``run`` on interleaved chunks of ``range(count)``, on the shared pool if any.

    >>> seen = []
    >>> map_chunks(seen.extend, 5, 1); seen
    [0, 1, 2, 3, 4]
    """
    idx = list(range(count))
    pool = shared_pool(workers) if count > 1 else None
    if pool is None:
        run(idx)
        return
    chunks = [idx[j::workers] for j in range(workers)]
    list(pool.map(run, chunks))
