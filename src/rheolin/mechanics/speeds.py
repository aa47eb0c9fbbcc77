"""Exact speeds of geared bodies and the base frequency ``w1`` (docs/conventions.md, harmonic sets).

Speed ratios through gear pairs are ratios of tooth counts, so they are kept as
:class:`fractions.Fraction`. The base frequency ``w1`` is the largest frequency of which every
generator (each body speed, each mesh frequency ``z * W``, each load frequency) is an integer
multiple: the rational gcd of the generators. All speeds here are *relative to the input speed*
(the input body has ratio 1); multiply by the input speed [rad/s] for physical values.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction

from ..errors import ModelError
from .willis import SpeedConstraint, fixed_pair, solve_speeds

__all__ = [
    "GearPair",
    "SpeedPlan",
    "propagate_speeds",
    "rational_gcd",
    "speed_plan",
    "train_speeds",
]

Rational = Fraction | int


@dataclass(frozen=True)
class GearPair:
    """Two gears in mesh for speed propagation.

    Parameters
    ----------
    pinion_body, gear_body
        Names of the bodies carrying the two gears.
    pinion_teeth, gear_teeth
        Tooth counts (positive integers).
    internal
        True for an internal (ring) gear pair: both turn the same way. External pairs reverse
        the direction of rotation.
    """

    pinion_body: str
    gear_body: str
    pinion_teeth: int
    gear_teeth: int
    internal: bool = False

    def __post_init__(self) -> None:
        for name in ("pinion_teeth", "gear_teeth"):
            z = getattr(self, name)
            if isinstance(z, bool) or not isinstance(z, int) or z <= 0:
                raise ModelError(f"`{name}` must be a positive integer, got {z!r}")
        if self.pinion_body == self.gear_body:
            raise ModelError(
                f"`pinion_body` and `gear_body` must differ, both are {self.pinion_body!r}"
            )


def rational_gcd(values: Iterable[Rational]) -> Fraction:
    """Largest positive rational ``g`` such that every value is an integer multiple of ``g``.

    Zeros are ignored; signs are irrelevant.

    Examples
    --------
    >>> rational_gcd([Fraction(23, 61), 1, Fraction(437, 2867)])
    Fraction(1, 2867)
    >>> rational_gcd([Fraction(3, 4), Fraction(9, 10)])
    Fraction(3, 20)
    """
    num, den = 0, 1
    for v in values:
        v = Fraction(v)
        if v == 0:
            continue
        num = math.gcd(num, abs(v.numerator))
        den = math.lcm(den, v.denominator)
    if num == 0:
        raise ModelError("`generators` must contain at least one nonzero frequency")
    return Fraction(num, den)


def propagate_speeds(
    input_body: str,
    pairs: Sequence[GearPair],
    bodies: Iterable[str] = (),
    fixed_ratios: Mapping[str, Rational] | None = None,
) -> dict[str, Fraction]:
    """Signed speed of every body relative to the input body, through the gear pairs.

    Parameters
    ----------
    input_body
        Body whose speed is the input speed (ratio 1).
    pairs
        Gear pairs; ``W_gear = -W_pinion * z_pinion / z_gear`` (external) or ``+`` (internal).
    bodies
        Further bodies to report; bodies reached by no pair get ratio 0 (not rotating) unless
        given in ``fixed_ratios``.
    fixed_ratios
        Bodies with a prescribed ratio (e.g. a housing, 0). Pairs must agree with them.

    Returns
    -------
    dict
        ``{body: Fraction}`` signed speed ratios (sign = direction about the common axis).

    Examples
    --------
    A two-stage reduction with hunting-tooth ratios 23:61 and 19:47:

    >>> r = propagate_speeds("in", [GearPair("in", "mid", 23, 61), GearPair("mid", "out", 19, 47)])
    >>> r["mid"], r["out"]
    (Fraction(-23, 61), Fraction(437, 2867))
    """
    ratios: dict[str, Fraction] = {input_body: Fraction(1)}
    for name, value in (fixed_ratios or {}).items():
        if name == input_body and Fraction(value) != 1:
            raise ModelError(f"`fixed_ratios[{name!r}]` conflicts with the input body (ratio 1)")
        ratios[name] = Fraction(value)
    adjacency: dict[str, list[tuple[str, Fraction]]] = {}
    for p in pairs:
        sign = 1 if p.internal else -1
        forward = Fraction(sign * p.pinion_teeth, p.gear_teeth)
        adjacency.setdefault(p.pinion_body, []).append((p.gear_body, forward))
        adjacency.setdefault(p.gear_body, []).append((p.pinion_body, 1 / forward))
    stack = list(ratios)
    while stack:
        body = stack.pop()
        for other, factor in adjacency.get(body, []):
            value = ratios[body] * factor
            if other in ratios:
                if ratios[other] != value:
                    raise ModelError(
                        f"gear pairs give body {other!r} two speeds ({ratios[other]} and "
                        f"{value} x input): the gear train is kinematically inconsistent"
                    )
                continue
            ratios[other] = value
            stack.append(other)
    for b in bodies:
        ratios.setdefault(b, Fraction(0))
    for p in pairs:
        for b in (p.pinion_body, p.gear_body):
            ratios.setdefault(b, Fraction(0))
    return ratios


@dataclass(frozen=True)
class SpeedPlan:
    """Exact speeds and harmonic generators of a model, relative to the input speed.

    Attributes
    ----------
    base
        ``w1 / input_speed`` as a Fraction.
    ratios
        Signed body speed ratios ``W_b / input_speed``.
    spin
        Integer spin harmonic ``s_b`` per body: ``W_b = s_b * w1``.
    mesh
        Integer mesh harmonic per gear pair (``z_pinion * |s_pinion|``), in ``pairs`` order.
    loads
        Integer harmonic of each extra load frequency, in the order given.
    sets
        Integer mesh harmonic per planetary set (``z_sun * |s_sun - s_carrier|``).
    """

    base: Fraction
    ratios: dict[str, Fraction]
    spin: dict[str, int]
    mesh: tuple[int, ...] = ()
    loads: tuple[int, ...] = field(default=())
    sets: dict[str, int] = field(default_factory=dict)

    @property
    def generators(self) -> list[int]:
        """Sorted positive generator harmonics: body spins, meshes and load frequencies."""
        g = {abs(s) for s in self.spin.values()} | {abs(m) for m in self.mesh}
        g |= {abs(n) for n in self.loads} | {abs(m) for m in self.sets.values()}
        return sorted(x for x in g if x != 0)

    def harmonic(self, ratio: Rational) -> int:
        """Harmonic index of a frequency given relative to the input speed.

        >>> speed_plan("a", []).harmonic(3)
        3
        """
        n = Fraction(ratio) / self.base
        if n.denominator != 1:
            raise ModelError(
                f"frequency {ratio} x input is not a multiple of w1 = {self.base} x input; "
                "include it in `load_ratios` when building the plan"
            )
        return int(n)


def train_speeds(
    input_body: str,
    pairs: Sequence[GearPair],
    bodies: Iterable[str] = (),
    fixed_ratios: Mapping[str, Rational] | None = None,
    carried: Sequence[SpeedConstraint] = (),
) -> dict[str, Fraction]:
    """:func:`propagate_speeds`, or with planetary sets (``carried``: the Willis constraints
    of their meshes, :mod:`rheolin.mechanics.willis`) the exact solution of every constraint.

    >>> from rheolin.mechanics.willis import set_constraints
    >>> cs = set_constraints("set", "sun", "ring", "c", ["p"], (21, 39, 99))
    >>> train_speeds("c", [GearPair("sun", "out", 30, 60)], [], {"ring": 0}, cs)["out"]
    Fraction(-20, 7)
    """
    if not carried:
        return propagate_speeds(input_body, pairs, bodies, fixed_ratios)
    fixed = [
        fixed_pair(p.pinion_body, p.gear_body, p.pinion_teeth, p.gear_teeth, p.internal,
                   f"the gear mesh {p.pinion_body!r}-{p.gear_body!r}")
        for p in pairs
    ]  # fmt: skip
    return solve_speeds(input_body, [*fixed, *carried], bodies, fixed_ratios)


def speed_plan(
    input_body: str,
    pairs: Sequence[GearPair],
    bodies: Iterable[str] = (),
    load_ratios: Iterable[Rational] = (),
    fixed_ratios: Mapping[str, Rational] | None = None,
    carried: Sequence[SpeedConstraint] = (),
    sets: Mapping[str, tuple[str, str, int]] | None = None,
) -> SpeedPlan:
    """Speeds, base frequency and integer harmonics of a geared model.

    Parameters
    ----------
    input_body, pairs, bodies, fixed_ratios
        As in :func:`propagate_speeds`.
    load_ratios
        Load frequencies relative to the input speed (e.g. ``2 * ratio`` of a body for a
        twice-per-revolution force); they take part in the gcd.
    carried, sets
        Planetary sets: their Willis constraints (:func:`train_speeds`), and per set its sun
        body, carrier body and sun tooth count (the mesh frequency
        ``z_s |W_sun - W_carrier|``).

    Examples
    --------
    >>> p = speed_plan("in", [GearPair("in", "mid", 23, 61), GearPair("mid", "out", 19, 47)])
    >>> p.base, p.spin["in"], p.spin["mid"], p.spin["out"], p.mesh
    (Fraction(1, 2867), 2867, -1081, 437, (65941, 20539))
    """
    ratios = train_speeds(input_body, pairs, bodies, fixed_ratios, carried)
    loads = [Fraction(x) for x in load_ratios]
    mesh_ratios = [p.pinion_teeth * abs(ratios[p.pinion_body]) for p in pairs]
    set_ratios = {n: z * abs(ratios[s] - ratios[c]) for n, (s, c, z) in (sets or {}).items()}
    base = rational_gcd([*ratios.values(), *mesh_ratios, *loads, *set_ratios.values()])
    spin = {b: int(r / base) for b, r in ratios.items()}
    mesh = tuple(int(m / base) for m in mesh_ratios)
    return SpeedPlan(
        base=base,
        ratios=ratios,
        spin=spin,
        mesh=mesh,
        loads=tuple(int(x / base) for x in loads),
        sets={n: int(m / base) for n, m in set_ratios.items()},
    )
