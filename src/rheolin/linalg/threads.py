"""BLAS limited to one thread for work made of many small dense products.

OpenBLAS's threads cost more than they bring on matrices of a few hundred rows (the lattice
kernels, a Campbell diagram's time-averaged modes: 0.7 s against 1.7-2.1 s wall for the
gearbox's 25 speeds on 2 cores, bench/stability.py), and they compete with the processes
of a parallel stability check for the same cores.
"""

from __future__ import annotations

import threading
from typing import Any

__all__ = ["single_thread_blas"]

_LOCK = threading.Lock()
_STATE: dict[str, Any] = {"depth": 0, "limits": None}


class single_thread_blas:
    """Limit BLAS to one thread while inside (re-entrant, and safe from several threads).

    The limit is process-wide (``threadpoolctl``): the first entry sets it and the last exit
    restores the thread counts found then, so overlapping uses from two threads (a diagram
    and an in-process stability check) neither restore early nor leave BLAS limited.

    >>> from threadpoolctl import threadpool_info
    >>> with single_thread_blas():
    ...     all(p["num_threads"] == 1 for p in threadpool_info() if p["user_api"] == "blas")
    True
    """

    def __enter__(self) -> None:
        from threadpoolctl import threadpool_limits

        with _LOCK:
            if _STATE["depth"] == 0:
                _STATE["limits"] = threadpool_limits(limits=1, user_api="blas")
            _STATE["depth"] += 1

    def __exit__(self, *exc: Any) -> None:
        with _LOCK:
            _STATE["depth"] -= 1
            if _STATE["depth"] == 0 and _STATE["limits"] is not None:
                _STATE["limits"].restore_original_limits()
                _STATE["limits"] = None
