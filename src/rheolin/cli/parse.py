"""Command-line values the CLI reads itself: input speeds and speed ranges."""

from __future__ import annotations

import math
import re

import numpy as np

from ..errors import ModelError
from ..io.units import UnitError, to_si

__all__ = ["parse_speed", "parse_speeds"]

_RANGE = re.compile(r"^\s*([-+0-9.eE]+)\s*:\s*([-+0-9.eE]+)\s*:\s*([-+0-9.eE]+)\s*(.*)$")


def parse_speed(text: str, option: str = "--speed") -> float:
    """``"3000rpm"`` -> rad/s; a bare number is rad/s.

    >>> round(parse_speed("3000rpm"), 6)
    314.159265
    """
    try:
        v = to_si(text, "speed")
    except UnitError as exc:
        raise ModelError(f"{option}: {exc}") from None
    if not v > 0:
        raise ModelError(f"{option}: the speed must be > 0, got {text!r}")
    return v


def parse_speeds(text: str, option: str = "--speeds", allow_zero: bool = False) -> np.ndarray:
    """``"500:6000:50rpm"`` (start:stop:step, stop included) or ``"1000,2000 rpm"`` -> rad/s.

    >>> (parse_speeds("1000:3000:1000rpm") * 30 / np.pi).round(6).tolist()
    [1000.0, 2000.0, 3000.0]
    """
    m = _RANGE.match(text)
    if m:
        unit = m.group(4).strip()
        try:
            start, stop, step = (float(m.group(i)) for i in (1, 2, 3))
        except ValueError:
            raise ModelError(f"{option}: cannot read {text!r}; write e.g. 500:6000:50rpm") from None
        if not (step > 0 and stop >= start and (start > 0 or (allow_zero and start == 0))):
            low = "0 <=" if allow_zero else "0 <"
            raise ModelError(f"{option}: need {low} start <= stop and step > 0, got {text!r}")
        count = math.floor((stop - start) / step + 1e-9) + 1
        if count > 10000:
            raise ModelError(f"{option}: {count} speeds is too many (at most 10000)")
        values = [start + i * step for i in range(count)]
    else:
        parts = [p for p in re.split(r"[,\s]+", text.strip()) if p]
        unit = ""
        if parts and re.match(r"^[A-Za-z/]", parts[-1]):
            unit = parts.pop()
        tail = re.match(r"^([-+0-9.eE]+)([A-Za-z/].*)$", parts[-1]) if parts else None
        if tail:
            parts[-1], unit = tail.group(1), tail.group(2)
        try:
            values = [float(p) for p in parts]
        except ValueError:
            raise ModelError(f"{option}: cannot read {text!r}; write e.g. 500:6000:50rpm") from None
        if not values:
            raise ModelError(f"{option}: no speeds in {text!r}")
    if allow_zero:
        return np.array(
            [0.0 if v == 0 else parse_speed(f"{v} {unit}".strip(), option) for v in values]
        )
    return np.array([parse_speed(f"{v} {unit}".strip(), option) for v in values])
