"""Memory budget: estimate before allocating, refuse with the estimate and what to change.

The budget is ``RHEOLIN_MEMORY_BUDGET`` (e.g. ``"8 GB"``, ``"512 MiB"``, or bytes) when set,
otherwise the smaller of 4 GiB and half the memory available now. The memory available is the
least of the machine's (``MemAvailable``), the room left under the process's address-space
limit (``ulimit -v``, ``RLIMIT_AS``) and under its control group's limit (cgroup v2
``memory.max``, v1 ``memory.limit_in_bytes``): a budget read from the machine alone would pass
an estimate that the process cannot allocate.

>>> parse_bytes("1.5 GB"), parse_bytes("512 MiB"), parse_bytes("1000")
(1500000000, 536870912, 1000)
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from .errors import ModelError

__all__ = [
    "DEFAULT_BUDGET",
    "MemoryBudgetError",
    "available_memory",
    "check_settings",
    "format_bytes",
    "memory_budget",
    "parse_bytes",
    "process_headroom",
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
        if not 0 < text <= 2.0**63:
            raise ValueError(f"a memory size must be positive and finite, got {text!r}")
        return int(text)
    if not isinstance(text, str):
        raise TypeError(
            f"a memory size is a number of bytes or a text like '4 GB', got {text!r:.60}"
        )
    m = re.fullmatch(r"\s*([+-]?[0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([A-Za-z]*)\s*", text)
    if not m or m.group(2).lower() not in _UNITS:
        raise ValueError(
            f"cannot read a memory size from {text!r}: use a number of bytes or a value with "
            f"one of the units {sorted(u for u in _UNITS if u)} (e.g. '4 GB')"
        )
    value = float(m.group(1)) * _UNITS[m.group(2).lower()]
    if not value > 0 or value > 2.0**63:
        raise ValueError(f"a memory size must be positive and finite, got {text!r}")
    return int(value)


def format_bytes(n: float) -> str:
    """``'1.2 GB'``."""
    for unit, size in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if abs(n) >= size:
            return f"{n / size:.3g} {unit}"
    return f"{int(n)} B"


def _machine_available() -> int | None:
    """The machine's memory available to new allocations [bytes] (``MemAvailable``)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):  # pragma: no cover - not Linux
        pass
    return None


def _status_bytes(key: str) -> int | None:
    """A ``kB`` line of ``/proc/self/status`` (``VmSize``) in bytes, or None."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):  # pragma: no cover - not Linux
        pass
    return None


def _address_space_room() -> int | None:
    """Room left under ``RLIMIT_AS`` (``ulimit -v``) [bytes], or None when unlimited."""
    try:
        import resource
    except ImportError:  # pragma: no cover - not POSIX
        return None
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft == resource.RLIM_INFINITY or soft <= 0:
        return None
    used = _status_bytes("VmSize") or 0
    return max(int(soft) - used, 0)


def _read_number(path: Path) -> int | None:
    try:
        text = path.read_text().strip()
    except (OSError, UnicodeDecodeError):
        return None
    return int(text) if text.isdigit() else None


#: A cgroup v1 limit at or above this is "no limit" (the kernel writes ``PAGE_COUNTER_MAX``).
_CGROUP_UNLIMITED = 2**60


def _cgroup_room(
    root: Path = Path("/sys/fs/cgroup"), listing: Path = Path("/proc/self/cgroup")
) -> int | None:
    """Room left under the process's control-group memory limit [bytes], or None.

    cgroup v2: ``memory.max`` minus ``memory.current`` of the process's group (and of each
    group above it: the tightest counts); cgroup v1: ``memory.limit_in_bytes`` minus
    ``memory.usage_in_bytes``.
    """
    try:
        lines = listing.read_text().splitlines()
    except OSError:
        return None
    rooms: list[int] = []
    for line in lines:
        parts = line.split(":", 2)
        if len(parts) != 3:
            continue
        controllers, rel = parts[1], parts[2].lstrip("/")
        if controllers == "":  # v2: walk up from the process's group to the root
            here = root / rel
            while True:
                limit = _read_number(here / "memory.max")
                used = _read_number(here / "memory.current")
                if limit is not None and used is not None:
                    rooms.append(max(limit - used, 0))
                if here == root or root not in here.parents:
                    break
                here = here.parent
        elif "memory" in controllers.split(","):
            for base in (root / "memory" / rel, root / "memory"):
                limit = _read_number(base / "memory.limit_in_bytes")
                used = _read_number(base / "memory.usage_in_bytes")
                if limit is not None and used is not None and limit < _CGROUP_UNLIMITED:
                    rooms.append(max(limit - used, 0))
                    break
    return min(rooms) if rooms else None


def process_headroom() -> dict[str, int]:
    """What limits new allocations now [bytes]: ``{"machine": ..., "address space": ...,
    "cgroup": ...}`` (only the limits that apply)."""
    out: dict[str, int] = {}
    for name, value in (
        ("machine", _machine_available()),
        ("address space", _address_space_room()),
        ("cgroup", _cgroup_room()),
    ):
        if value is not None:
            out[name] = int(value)
    return out


def available_memory() -> int | None:
    """Memory this process can still allocate [bytes]: the least of the machine's available
    memory, the room under its address-space limit and under its control group's limit
    (:func:`process_headroom`); None when none is known."""
    room = process_headroom()
    return min(room.values()) if room else None


def _env_bytes(name: str) -> int | None:
    """Bytes from the environment variable ``name``, or None when it is unset; a
    :class:`~rheolin.errors.ModelError` naming the variable when it cannot be read (a user
    error, not a bug)."""
    text = os.environ.get(name)
    if not text:
        return None
    try:
        return parse_bytes(text)
    except ValueError as exc:
        raise ModelError(f"{name}: {exc}") from None


#: The least default budget when the machine reports little available memory (the page cache
#: that ``MemAvailable`` leaves out can usually be reclaimed); never above a process limit.
_FLOOR = 256 * 2**20


def _limited(budget: int) -> int:
    """``budget`` capped by the process's own limits (address space, cgroup): no budget
    above what the process can ever allocate."""
    room = process_headroom()
    hard = [v for k, v in room.items() if k != "machine"]
    return int(min([budget, *hard]))


def _default(share: float, cap: int | None) -> int:
    room = process_headroom()
    if not room:
        return DEFAULT_BUDGET
    hard = [v for k, v in room.items() if k != "machine"]
    machine = room.get("machine")
    soft = DEFAULT_BUDGET if machine is None else max(int(share * machine), _FLOOR)
    if cap is not None:
        soft = min(soft, cap)
    return int(min([soft, *(int(share * h) for h in hard)]))


def memory_budget(override: str | int | float | None = None) -> int:
    """The budget in bytes: ``override``, else ``RHEOLIN_MEMORY_BUDGET``, else the smaller of
    :data:`DEFAULT_BUDGET` and half the memory available; never above the room left under
    the process's own limits (``ulimit -v``, cgroup)."""
    if override is not None:
        return _limited(parse_bytes(override))
    env = _env_bytes("RHEOLIN_MEMORY_BUDGET")
    if env is not None:
        return _limited(env)
    return _default(0.5, DEFAULT_BUDGET)


def solve_budget(override: str | int | float | None = None) -> int:
    """The budget of one harmonic-balance solve [bytes]: ``override``, else
    ``RHEOLIN_SOLVE_MEMORY``, else most (:data:`SOLVE_SHARE`) of the memory available now;
    never above the room left under the process's own limits.

    Larger than :func:`memory_budget`'s default, which guards optional extras (a stability
    check); a solve's factors are what the machine is there for.
    """
    if override is not None:
        return _limited(parse_bytes(override))
    env = _env_bytes("RHEOLIN_SOLVE_MEMORY")
    if env is not None:
        return _limited(env)
    return _default(SOLVE_SHARE, None)


def check_settings() -> None:
    """Read the budget variables once (``RHEOLIN_MEMORY_BUDGET``, ``RHEOLIN_SOLVE_MEMORY``):
    a value that cannot be read is a :class:`~rheolin.errors.ModelError` naming it, raised
    before any work."""
    _env_bytes("RHEOLIN_MEMORY_BUDGET")
    _env_bytes("RHEOLIN_SOLVE_MEMORY")
