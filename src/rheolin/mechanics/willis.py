"""Exact speeds of gear trains with planetary sets: the Willis equation over the rationals.

A gear pair on fixed axes ties two speeds, ``z_a W_a + z_b W_b = 0`` (external; ``-`` for an
internal pair). A pair whose axes the carrier ``c`` carries (a planet with its sun or ring) does
the same relative to the carrier, ``z_a (W_a - W_c) +- z_b (W_b - W_c) = 0``; the sun and the
ring meshes of one planet give together Willis' equation
``z_s (W_s - W_c) + z_r (W_r - W_c) = 0``, so a planetary set leaves one speed free. The input
body (speed 1) and the bodies given a speed (a held member: 0) close the system, which is solved
exactly with :class:`fractions.Fraction`. Bodies that no constraint reaches from the input do not
turn (a housing), as for parallel gear trains.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction

from ..errors import ModelError

__all__ = ["SpeedConstraint", "carried_pair", "fixed_pair", "set_constraints", "solve_speeds"]


@dataclass(frozen=True)
class SpeedConstraint:
    """``sum_b coefficients[b] * W_b = 0``, with a label naming the item it comes from."""

    coefficients: tuple[tuple[str, Fraction], ...]
    label: str

    @property
    def bodies(self) -> list[str]:
        """The bodies whose speeds it ties."""
        return [b for b, _ in self.coefficients]


def _teeth(z: object, field: str) -> int:
    if isinstance(z, bool) or not isinstance(z, int) or z <= 0:
        raise ModelError(f"`{field}` must be a positive integer, got {z!r}")
    return z


def fixed_pair(a: str, b: str, za: int, zb: int, internal: bool, label: str) -> SpeedConstraint:
    """Two gears on fixed axes: ``z_a W_a + z_b W_b = 0`` (``-`` when internal).

    >>> fixed_pair("in", "out", 20, 40, False, "mesh 'm'").coefficients
    (('in', Fraction(20, 1)), ('out', Fraction(40, 1)))
    """
    za, zb = _teeth(za, "pinion_teeth"), _teeth(zb, "gear_teeth")
    sign = -1 if internal else 1
    return SpeedConstraint(((a, Fraction(za)), (b, Fraction(sign * zb))), label)


def carried_pair(
    a: str, b: str, carrier: str, za: int, zb: int, internal: bool, label: str
) -> SpeedConstraint:
    """Two gears whose axes turn with ``carrier``: ``z_a (W_a - W_c) + z_b (W_b - W_c) = 0``
    (``-`` before ``z_b`` when internal).

    >>> c = carried_pair("sun", "planet", "carrier", 20, 30, False, "set 'p'")
    >>> dict(c.coefficients)
    {'sun': Fraction(20, 1), 'planet': Fraction(30, 1), 'carrier': Fraction(-50, 1)}
    """
    za, zb = _teeth(za, "sun_teeth"), _teeth(zb, "planet_teeth")
    sign = -1 if internal else 1
    coef = {a: Fraction(za), b: Fraction(sign * zb)}
    coef[carrier] = coef.get(carrier, Fraction(0)) - za - sign * zb
    return SpeedConstraint(tuple(coef.items()), label)


def set_constraints(
    label: str,
    sun: str,
    ring: str,
    carrier: str,
    planets: Sequence[str],
    teeth: tuple[int, int, int],
) -> list[SpeedConstraint]:
    """The sun and ring meshes of every planet of a set (teeth: sun, planet, ring).

    >>> cs = set_constraints("set 'p'", "s", "r", "c", ["p0", "p1", "p2"], (21, 39, 99))
    >>> solve_speeds("c", cs, fixed_ratios={"r": 0})["s"]
    Fraction(40, 7)
    """
    zs, zp, zr = teeth
    out = []
    for p in planets:
        out.append(carried_pair(sun, p, carrier, zs, zp, False, label))
        out.append(carried_pair(ring, p, carrier, zr, zp, True, label))
    return out


def solve_speeds(
    input_body: str,
    constraints: Sequence[SpeedConstraint],
    bodies: Iterable[str] = (),
    fixed_ratios: Mapping[str, Fraction | int] | None = None,
) -> dict[str, Fraction]:
    """Signed speed of every body relative to the input body (exact).

    Parameters
    ----------
    input_body
        Body turning at the input speed (ratio 1).
    constraints
        Speed constraints of the meshes (:func:`fixed_pair`, :func:`carried_pair`).
    bodies
        Further bodies to report.
    fixed_ratios
        Bodies with a given speed ratio: a held member (0), a second drive.

    Raises
    ------
    ModelError
        A constraint that contradicts the earlier ones (kinematically inconsistent train, named
        by its label), or speeds the input does not determine (a planetary set with no member
        held or driven).

    Examples
    --------
    Ring held, sun driven, 20/30/80 teeth: the carrier turns at ``z_s / (z_s + z_r)``.

    >>> cs = [carried_pair("sun", "p", "c", 20, 30, False, "sun mesh"),
    ...       carried_pair("ring", "p", "c", 80, 30, True, "ring mesh")]
    >>> r = solve_speeds("sun", cs, fixed_ratios={"ring": 0})
    >>> r["c"], r["p"]
    (Fraction(1, 5), Fraction(-1, 3))
    >>> solve_speeds("sun", cs)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rheolin.errors.ModelError: the input speed does not determine the speeds of ['c', 'p', ...
    """
    names: list[str] = [input_body]
    fixed = {k: Fraction(v) for k, v in (fixed_ratios or {}).items()}
    if fixed.get(input_body, Fraction(1)) != 1:
        raise ModelError(f"`speed_ratio` of the input body {input_body!r} must be 1")
    for c in constraints:
        names += c.bodies
    names += list(fixed) + list(bodies)
    order = list(dict.fromkeys(names))
    col = {b: i for i, b in enumerate(order)}
    rows: list[tuple[dict[int, Fraction], Fraction, str]] = [
        ({col[input_body]: Fraction(1)}, Fraction(1), "the input speed")
    ]
    rows += [({col[b]: Fraction(1)}, v, f"`speed_ratio` of {b!r}") for b, v in fixed.items()]
    for c in constraints:
        row: dict[int, Fraction] = {}
        for b, v in c.coefficients:
            row[col[b]] = row.get(col[b], Fraction(0)) + v
        rows.append(({k: v for k, v in row.items() if v}, Fraction(0), c.label))
    pivots: dict[int, tuple[dict[int, Fraction], Fraction]] = {}  # pivot column -> its row
    for row, rhs, label in rows:
        row, rhs = dict(row), Fraction(rhs)
        for p, (prow, prhs) in pivots.items():  # reduce by the rows so far (kept reduced)
            f = row.pop(p, None)
            if f:
                for k, v in prow.items():
                    if k != p:
                        row[k] = row.get(k, Fraction(0)) - f * v
                rhs -= f * prhs
        row = {k: v for k, v in row.items() if v}
        if not row:
            if rhs != 0:
                raise ModelError(
                    f"{label} gives speeds that contradict the other gear meshes and held or "
                    "driven bodies: the gear train is kinematically inconsistent"
                )
            continue
        p = min(row)
        scale = row[p]
        row = {k: v / scale for k, v in row.items()}
        rhs /= scale
        for q, (qrow, qrhs) in list(pivots.items()):  # keep the earlier rows reduced in p
            f = qrow.get(p)
            if f:
                new = {
                    k: qrow.get(k, Fraction(0)) - f * row.get(k, Fraction(0))
                    for k in set(qrow) | set(row)
                }
                pivots[q] = ({k: v for k, v in new.items() if v}, qrhs - f * rhs)
        pivots[p] = (row, rhs)
    free = [i for i in range(len(order)) if i not in pivots]
    _check_determined(order, free, rows, 1 + len(fixed), pivots)
    out = {b: Fraction(0) for b in order}
    for p, (_, rhs) in pivots.items():
        out[order[p]] = rhs  # free speeds are 0: bodies the input does not reach
    return out


def _check_determined(
    order: list[str],
    free: list[int],
    rows: list[tuple[dict[int, Fraction], Fraction, str]],
    anchored: int,
    pivots: Mapping[int, tuple[dict[int, Fraction], Fraction]],
) -> None:
    """A free speed in a train that the input or a held body reaches is undetermined; free
    speeds of trains nothing reaches are simply 0 (they do not turn). ``rows[:anchored]`` are
    the input and the given speeds."""
    parent = list(range(len(order)))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for row, _, _ in rows[anchored:]:
        cols = list(row)
        for k in cols[1:]:
            parent[root(k)] = root(cols[0])
    anchors = {root(next(iter(row))) for row, _, _ in rows[:anchored]}
    loose = {root(k) for k in free} & anchors
    if not loose:
        return
    open_ = {k for k in free if root(k) in loose}
    open_ |= {p for p, (prow, _) in pivots.items() if any(k in open_ for k in prow)}
    bodies = sorted(order[i] for i in open_)
    labels = [lab for row, _, lab in rows[anchored:] if any(k in open_ for k in row)]
    raise ModelError(
        f"the input speed does not determine the speeds of {bodies} "
        f"({', '.join(dict.fromkeys(labels))}): hold a member (speed_ratio = 0) or drive a "
        "second one"
    )
