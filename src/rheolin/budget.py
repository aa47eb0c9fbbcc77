"""Memory budget: estimate before allocating, refuse with the estimate and what to change.

The budget is ``RHEOLIN_MEMORY_BUDGET`` (e.g. ``"8 GB"``, ``"512 MiB"``, or bytes) when set,
otherwise the smaller of 4 GiB and half the memory available now.

>>> parse_bytes("1.5 GB"), parse_bytes("512 MiB"), parse_bytes("1000")
(1500000000, 536870912, 1000)
"""

from __future__ import annotations

import os
import re

__all__ = [
    "DEFAULT_BUDGET",
    "MemoryBudgetError",
    "available_memory",
    "format_bytes",
    "memory_budget",
    "parse_bytes",
    "solve_budget",
]

#: Share of the memory available now that a harmonic-balance solve may use by default (the
#: factors of ``A0(n)`` are held while they fit it, see :mod:`rheolin.linalg.memory`).
SOLVE_SHARE = 0.8

#: The default budget when nothing is set and the machine has room [bytes].
DEFAULT_BUDGET = 4 * 2**30

_UNITS = {
    "": 1,
    "b": 1,
    "kb": 10**3,
    "mb": 10**6,
    "gb": 10**9,
    "tb": 10**12,
    "kib": 2**10,
    "mib": 2**20,
    "gib": 2**30,
    "tib": 2**40,
}


class MemoryBudgetError(MemoryError, ValueError):
    """A computation would exceed the memory budget (raised before allocating)."""


def parse_bytes(text: str | int | float) -> int:
    """Bytes from ``"4 GB"``, ``"512MiB"`` or a number."""
    if isinstance(text, int | float) and not isinstance(text, bool):
        if text <= 0:
            raise ValueError(f"a memory size must be positive, got {text!r}")
        return int(text)
    m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([A-Za-z]*)\s*", str(text))
    if not m or m.group(2).lower() not in _UNITS:
        raise ValueError(
            f"cannot read a memory size from {text!r}: use a number of bytes or a value with "
            f"one of the units {sorted(u for u in _UNITS if u)} (e.g. '4 GB')"
        )
    value = float(m.group(1)) * _UNITS[m.group(2).lower()]
    if value <= 0:
        raise ValueError(f"a memory size must be positive, got {text!r}")
    return int(value)


def format_bytes(n: float) -> str:
    """``'1.2 GB'``."""
    for unit, size in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if abs(n) >= size:
            return f"{n / size:.3g} {unit}"
    return f"{int(n)} B"


def available_memory() -> int | None:
    """Memory available to new allocations [bytes] (Linux ``MemAvailable``), or None."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:  # pragma: no cover - not Linux
        pass
    return None


def _env_bytes(name: str) -> int | None:
    """Bytes from the environment variable ``name``, or None when it is unset."""
    text = os.environ.get(name)
    if not text:
        return None
    try:
        return parse_bytes(text)
    except ValueError as exc:
        raise ValueError(f"{name}: {exc}") from None


def memory_budget(override: str | int | float | None = None) -> int:
    """The budget in bytes: ``override``, else ``RHEOLIN_MEMORY_BUDGET``, else the default."""
    if override is not None:
        return parse_bytes(override)
    env = _env_bytes("RHEOLIN_MEMORY_BUDGET")
    if env is not None:
        return env
    avail = available_memory()
    if avail is None:
        return DEFAULT_BUDGET
    return int(min(DEFAULT_BUDGET, max(avail // 2, 256 * 2**20)))


def solve_budget(override: str | int | float | None = None) -> int:
    """The budget of one harmonic-balance solve [bytes]: ``override``, else
    ``RHEOLIN_SOLVE_MEMORY``, else most (:data:`SOLVE_SHARE`) of the memory available now.

    Larger than :func:`memory_budget`'s default, which guards optional extras (a stability
    check); a solve's factors are what the machine is there for.
    """
    if override is not None:
        return parse_bytes(override)
    env = _env_bytes("RHEOLIN_SOLVE_MEMORY")
    if env is not None:
        return env
    avail = available_memory()
    if avail is None:
        return DEFAULT_BUDGET
    return int(max(SOLVE_SHARE * avail, 256 * 2**20))
