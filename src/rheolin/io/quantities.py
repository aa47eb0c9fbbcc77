"""Unit-checked field types of the model file: a value (a number in SI or a quantity string)
converted to SI by pint when pydantic validates it, with its sign or range checked.

The ``Annotated`` types at the end (``LengthPos``, ``VecLength``, ``ShaftDiameter``, ...) are
the field types :mod:`rheolin.io.schema` declares its tables with; the functions build them.

>>> from pydantic import TypeAdapter
>>> TypeAdapter(LengthPos).validate_python("35 mm")
0.035
>>> TypeAdapter(VecLength).validate_python("0 300 600 mm")
[0.0, 0.3, 0.6]
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Annotated, Any

import numpy as np
from pydantic import BeforeValidator, Field

from .units import UnitError, to_si, unit_registry

__all__ = [
    "MAX_PLAIN_DISK_SIZE",
    "MAX_PLAIN_SHAFT_DIAMETER",
    "angle_between",
    "fraction_text",
    "hertz_stiffness",
    "inertia_matrix",
    "plain_length_at_most",
    "quantity",
    "vector",
]

_LIST_TEXT = re.compile(r"^\s*\[?\s*([-+0-9.eE,\s]+?)\s*\]?\s+([A-Za-z][^\[\]]*)$")


def quantity(kind: str, sign: str = "") -> Callable[[Any], float]:
    """A converter to an SI float of ``kind`` (a key of :data:`rheolin.io.units.DIMENSIONS`);
    ``sign`` ``"+"`` refuses values <= 0, ``"0+"`` values < 0.

    >>> quantity("mass", "+")("2.5 kg")
    2.5
    """

    def convert(value: Any) -> float:
        v = to_si(value, kind)
        if sign == "+" and not v > 0:
            raise UnitError(f"must be > 0, got {value!r}")
        if sign == "0+" and not v >= 0:
            raise UnitError(f"must be >= 0, got {value!r}")
        return v

    return convert


def angle_between(low_deg: float, high_deg: float) -> Callable[[Any], float]:
    """An angle in the open interval ``(low_deg, high_deg)`` degrees (stored in radians).

    >>> round(angle_between(0.0, 90.0)("20 deg"), 6)
    0.349066
    """

    def convert(value: Any) -> float:
        v = to_si(value, "angle")
        if not np.radians(low_deg) < v < np.radians(high_deg):
            raise UnitError(
                f"must lie strictly between {low_deg:g} and {high_deg:g} deg, got {value!r}"
                + (" (a plain number is radians)" if not isinstance(value, str) else "")
            )
        return v

    return convert


def plain_length_at_most(limit: float, what: str) -> Callable[[Any], Any]:
    """Refuse a plain number (metres) above ``limit`` m where units were surely forgotten
    (``outer_diameter = 30`` is 30 m, not 30 mm); values with units pass unchanged."""

    def check(value: Any) -> Any:
        items = value if isinstance(value, list) else [value]
        for x in items:
            if isinstance(x, int | float) and not isinstance(x, bool) and abs(x) > limit:
                raise UnitError(
                    f"a plain number is metres: {x!r} m is not a plausible {what} (allowed: up "
                    f"to {limit:g} m); give units, e.g. '{x:g} mm'"
                )
        return value

    return check


def vector(kind: str, sign: str = "") -> Callable[[Any], list[float]]:
    """A converter of one value, a list, or a text ``"0 20 50 mm"`` to a list of SI floats.

    >>> vector("length")("[0, 20, 50] mm")
    [0.0, 0.02, 0.05]
    """
    one = quantity(kind, sign)

    def convert(value: Any) -> list[float]:
        if isinstance(value, str):  # "0 20 50 90 mm" or "[0, 20, 50] mm"
            m = _LIST_TEXT.match(value)
            if not m:
                return [one(value)]
            nums = [x for x in re.split(r"[,\s]+", m.group(1)) if x]
            return [one(f"{x} {m.group(2)}") for x in nums]
        if isinstance(value, list):
            out = []
            for i, x in enumerate(value):
                try:
                    out.append(one(x))
                except UnitError as exc:
                    raise UnitError(f"entry {i}: {exc}") from None
            return out
        return [one(value)]

    return convert


def fraction_text(value: Any) -> str:
    """A number or a fraction text as the text of an exact fraction.

    >>> fraction_text("2/4"), fraction_text(0.5)
    ('1/2', '1/2')
    """
    from fractions import Fraction

    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise ValueError(f"expected a number or a fraction like '1/2', got {value!r}")
    try:
        return str(Fraction(str(value).strip()))
    except (ValueError, ZeroDivisionError):
        raise ValueError(f"expected a number or a fraction like '1/2', got {value!r}") from None


def inertia_matrix(value: list[Any] | None, definite: bool = True) -> list[Any] | None:
    """3 values or a 3x3 symmetric matrix of inertias, positive (semi-)definite.

    >>> inertia_matrix(["100 kg*cm^2", 0.01, 0.02])
    [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.02]]
    """
    if value is None:
        return None
    conv = quantity("inertia")
    try:
        rows = [[conv(x) for x in r] for r in value] if isinstance(value[0], list) else None
        J = np.array(rows) if rows is not None else np.diag([conv(x) for x in value])
    except (UnitError, TypeError, IndexError) as exc:
        raise ValueError(f"must be 3 values or a 3x3 matrix of inertias: {exc}") from None
    if J.shape != (3, 3):
        raise ValueError(f"must be 3 values or a 3x3 matrix, got shape {J.shape}")
    scale = float(np.abs(J).max(initial=0.0))
    if not np.allclose(J, J.T, rtol=0.0, atol=1e-9 * scale):
        raise ValueError("the inertia (mass) matrix must be symmetric")
    eig = np.linalg.eigvalsh(0.5 * (J + J.T))
    if definite and (scale == 0.0 or eig.min() <= 0.0):
        raise ValueError(f"the inertia (mass) matrix must be positive definite; eigenvalues {eig}")
    if eig.min() < -1e-12 * scale:
        raise ValueError(
            "the inertia (mass) matrix must be positive definite (or semi-definite for a "
            f"point mass); eigenvalues {eig}"
        )
    return J.tolist()


def hertz_stiffness(value: Any, exponent: float) -> float:
    """``K`` of ``F = K delta^n`` [N/m^n]: a number (SI) or a quantity string.

    >>> round(hertz_stiffness("1e4 N/mm^1.5", 1.5))  # 1e4 * 1000**1.5
    316227766
    """
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise ValueError(f"expected a number (SI, N/m^{exponent:g}) or a quantity, got {value!r}")
    if isinstance(value, str):
        try:
            out = float(unit_registry()(value).to(f"N/m**{exponent!r}").magnitude)
        except Exception as exc:
            raise ValueError(
                f"expected a stiffness in N/m^{exponent:.4g} (the exponent of "
                f"{'ball' if exponent == 1.5 else 'roller'} contact), got {value!r}: {exc}"
            ) from None
    else:
        out = float(value)
    if not (np.isfinite(out) and out > 0):
        raise ValueError(f"must be > 0, got {value!r}")
    return out


Angle = Annotated[float, BeforeValidator(quantity("angle"))]
PressureAngle = Annotated[float, BeforeValidator(angle_between(0.0, 90.0))]
HelixAngle = Annotated[float, BeforeValidator(angle_between(-90.0, 90.0))]
AreaPos = Annotated[float, BeforeValidator(quantity("area", "+"))]
CoupleUnbalanceNonNeg = Annotated[float, BeforeValidator(quantity("couple_unbalance", "0+"))]
DampingNonNeg = Annotated[float, BeforeValidator(quantity("damping", "0+"))]
DensityPos = Annotated[float, BeforeValidator(quantity("density", "+"))]
DensityNonNeg = Annotated[float, BeforeValidator(quantity("density", "0+"))]
ForcePos = Annotated[float, BeforeValidator(quantity("force", "+"))]
LengthPos = Annotated[float, BeforeValidator(quantity("length", "+"))]
Length = Annotated[float, BeforeValidator(quantity("length"))]
LengthNonNeg = Annotated[float, BeforeValidator(quantity("length", "0+"))]
MassPos = Annotated[float, BeforeValidator(quantity("mass", "+"))]
MassNonNeg = Annotated[float, BeforeValidator(quantity("mass", "0+"))]
PressurePos = Annotated[float, BeforeValidator(quantity("pressure", "+"))]
SecondMomentPos = Annotated[float, BeforeValidator(quantity("second_moment", "+"))]
SpeedPos = Annotated[float, BeforeValidator(quantity("speed", "+"))]
StiffnessNonNeg = Annotated[float, BeforeValidator(quantity("stiffness", "0+"))]
TimeNonNeg = Annotated[float, BeforeValidator(quantity("time", "0+"))]
UnbalanceNonNeg = Annotated[float, BeforeValidator(quantity("unbalance", "0+"))]
ViscosityPos = Annotated[float, BeforeValidator(quantity("viscosity", "+"))]
VecAcceleration = Annotated[list[float], BeforeValidator(vector("acceleration"))]
VecDimensionless = Annotated[list[float], BeforeValidator(vector("dimensionless"))]
VecForce = Annotated[list[float], BeforeValidator(vector("force"))]
VecForceNonNeg = Annotated[list[float], BeforeValidator(vector("force", "0+"))]
VecLength = Annotated[list[float], BeforeValidator(vector("length"))]
VecLengthPos = Annotated[list[float], BeforeValidator(vector("length", "+"))]
VecLengthNonNeg = Annotated[list[float], BeforeValidator(vector("length", "0+"))]
VecStiffnessPos = Annotated[list[float], BeforeValidator(vector("stiffness", "+"))]
#: Largest plain-number shaft diameter [m]: the largest marine shafts are about 1 m.
MAX_PLAIN_SHAFT_DIAMETER = 5.0
#: Largest plain-number disk dimension [m] (large hydro-generator rotors).
MAX_PLAIN_DISK_SIZE = 25.0
ShaftDiameter = Annotated[
    VecLengthPos, BeforeValidator(plain_length_at_most(MAX_PLAIN_SHAFT_DIAMETER, "shaft diameter"))
]
ShaftBore = Annotated[
    VecLengthNonNeg,
    BeforeValidator(plain_length_at_most(MAX_PLAIN_SHAFT_DIAMETER, "shaft diameter")),
]
DiskSize = Annotated[
    LengthPos, BeforeValidator(plain_length_at_most(MAX_PLAIN_DISK_SIZE, "disk size"))
]
DiskBore = Annotated[
    LengthNonNeg, BeforeValidator(plain_length_at_most(MAX_PLAIN_DISK_SIZE, "disk size"))
]
VecMoment = Annotated[list[float], BeforeValidator(vector("moment"))]
VecPressurePos = Annotated[list[float], BeforeValidator(vector("pressure", "+"))]
VecDensityNonNeg = Annotated[list[float], BeforeValidator(vector("density", "0+"))]
VecSpeedNonNeg = Annotated[list[float], BeforeValidator(vector("speed", "0+"))]
Index = Annotated[int, Field(ge=0, strict=True)]
Name = Annotated[str, Field(min_length=1)]
Ratio = Annotated[str, BeforeValidator(fraction_text)]
Raw = float | int | str | list[Any]  # matrices whose units depend on components
