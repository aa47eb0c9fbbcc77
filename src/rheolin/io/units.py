"""Unit strings at the file boundary: ``"3000 rpm"``, ``"2e8 N/m"``, ``"5 g*mm"`` -> SI floats.

Plain numbers are taken as SI. pint treats radians as dimensionless, so a rotational speed is
converted through ``rad/s``; a speed written in ``Hz`` means revolutions per second (``turn/s``),
never ``rad/s``.

>>> to_si("3000 rpm", "speed")
314.1592653589793
>>> round(to_si("5 g*mm", "unbalance"), 12)
5e-06
>>> to_si(2e8, "stiffness")
200000000.0
>>> to_si("50 Hz", "speed") == to_si("3000 rpm", "speed")
True
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

__all__ = ["DIMENSIONS", "SI_RANGE", "UnitError", "to_si", "unit_registry"]

#: Quantity kinds: SI unit they convert to, and an example for error messages.
DIMENSIONS: dict[str, tuple[str, str]] = {
    "length": ("m", "35 mm"),
    "mass": ("kg", "2.5 kg"),
    "inertia": ("kg*m**2", "0.01 kg*m^2"),
    "speed": ("rad/s", "3000 rpm"),
    "angle": ("rad", "20 deg"),
    "pressure": ("Pa", "210 GPa"),
    "density": ("kg/m**3", "7850 kg/m^3"),
    "time": ("s", "2e-5 s"),
    "unbalance": ("kg*m", "5 g*mm"),
    "couple_unbalance": ("kg*m**2", "500 g*mm^2"),
    "stiffness": ("N/m", "2e8 N/m"),
    "rotational_stiffness": ("N*m/rad", "1e4 N*m/rad"),
    "cross_stiffness": ("N/rad", "1e5 N/rad"),
    "damping": ("N*s/m", "2000 N*s/m"),
    "rotational_damping": ("N*m*s/rad", "1 N*m*s/rad"),
    "cross_damping": ("N*s/rad", "10 N*s/rad"),
    "mass_coefficient": ("kg", "0.5 kg"),
    "rotational_mass_coefficient": ("kg*m**2", "0.01 kg*m^2"),
    "cross_mass_coefficient": ("kg*m", "0.1 kg*m"),
    "force": ("N", "100 N"),
    "moment": ("N*m", "10 N*m"),
    "acceleration": ("m/s**2", "9.81 m/s^2"),
    "area": ("m**2", "1.2 cm^2"),
    "second_moment": ("m**4", "12 cm^4"),
    "frequency": ("Hz", "5 kHz"),
    "viscosity": ("Pa*s", "0.03 Pa*s"),
    "dimensionless": ("", "0.3"),
}


#: Nonzero magnitudes accepted in SI units: beyond them products of a few quantities (mass x
#: speed squared x length...) overflow or underflow double precision.
SI_RANGE = (1e-24, 1e24)


class UnitError(ValueError):
    """A value that is not a number or quantity of the expected kind."""


@lru_cache(maxsize=1)
def unit_registry() -> Any:
    import pint

    return pint.UnitRegistry()


def to_si(value: Any, kind: str) -> float:
    """Convert a number (SI) or a quantity string to an SI float of the given ``kind``.

    Raises
    ------
    UnitError
        With a message that states the expected unit and an example.
    """
    unit, example = DIMENSIONS[kind]
    if isinstance(value, bool):
        raise UnitError(f"expected a {kind.replace('_', ' ')} like {example!r}, got {value!r}")
    if isinstance(value, int | float):
        out = float(value)
    elif isinstance(value, str):
        out = _parse(value, kind, unit, example)
    else:
        raise UnitError(
            f"expected a number (SI) or a string like {example!r}, got {type(value).__name__}"
        )
    if not math.isfinite(out):
        raise UnitError(f"must be finite, got {value!r}")
    if out != 0.0 and not SI_RANGE[0] <= abs(out) <= SI_RANGE[1]:
        raise UnitError(
            f"{value!r} is {out:.3g} {unit or '(no unit)'}: outside the magnitudes rheolin "
            f"computes with ({SI_RANGE[0]:g} to {SI_RANGE[1]:g} in SI units, or 0)"
        )
    return out


def _parse(text: str, kind: str, unit: str, example: str) -> float:
    ureg = unit_registry()
    try:
        q = ureg.Quantity(text.strip())
    except Exception:
        raise UnitError(f"cannot read {text!r} as a quantity; write it like {example!r}") from None
    if not isinstance(q, ureg.Quantity):  # a bare number inside a string
        return float(q)
    if kind == "speed" and "hertz" in str(q.units):
        # a rotational speed in Hz means revolutions per second (pint: Hz == rad/s)
        if q.dimensionality != ureg.Quantity("1 Hz").dimensionality:
            raise UnitError(f"expected a speed like {example!r}, got {text!r}")
        return float(q.to("Hz").magnitude) * 2.0 * math.pi
    target = ureg.Quantity(1.0, unit) if unit else ureg.Quantity(1.0)
    if unit and q.dimensionless and str(q.units) == "dimensionless":
        raise UnitError(
            f"expected a {kind.replace('_', ' ')} in {unit}, got {text!r} without a unit; "
            f"write it like {example!r} (plain TOML numbers, not strings, are SI)"
        )
    if q.dimensionality != target.dimensionality:
        raise UnitError(
            f"expected a {kind.replace('_', ' ')} in {unit or 'no unit'} (e.g. {example!r}), "
            f"got {text!r} with dimension {q.dimensionality}"
        )
    return float(q.to(unit).magnitude) if unit else float(q.to("dimensionless").magnitude)
