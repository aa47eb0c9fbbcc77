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
]

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


def memory_budget(override: str | int | float | None = None) -> int:
    """The budget in bytes: ``override``, else ``RHEOLIN_MEMORY_BUDGET``, else the default."""
    if override is not None:
        return parse_bytes(override)
    env = os.environ.get("RHEOLIN_MEMORY_BUDGET")
    if env:
        try:
            return parse_bytes(env)
        except ValueError as exc:
            raise ValueError(f"RHEOLIN_MEMORY_BUDGET: {exc}") from None
    avail = available_memory()
    if avail is None:
        return DEFAULT_BUDGET
    return int(min(DEFAULT_BUDGET, max(avail // 2, 256 * 2**20)))
