"""Load-dependent joints: rolling-element bearings and gear meshes whose stiffness depends on
the load they carry (the laws; the operating point is found in :mod:`rheolin.mechanics.preload`).

Rolling-element bearings (radial; the force acts in the bearing plane, normal to the axis):

* ``law="elements"`` (Harris, *Rolling Bearing Analysis*, ch. 7): ``Z`` rolling elements at
  angles ``psi_i = angle + 2 pi i / Z``; element ``i`` is compressed by
  ``delta_i = e_i . d - c`` (``d`` the radial displacement of the inner ring relative to the
  outer, ``e_i`` the element's direction, ``c`` the radial clearance) and carries
  ``Q_i = K_n <delta_i>^n`` (``<x> = max(x, 0)``): ``n = 3/2`` for point contact (ball),
  ``10/9`` for line contact (roller, Palmgren). The force on the inner ring is
  ``F = -sum Q_i e_i`` and the tangent stiffness ``sum n K_n <delta_i>^(n-1) e_i e_i^T``:
  anisotropic, and zero along directions no loaded element supports. The elements are held
  at fixed angles (the cage's varying compliance is not modelled).
* ``law="radial"``: one lumped law for the whole bearing, ``|F| = K <|d| - c>^n`` along
  ``d`` (isotropic): tangent ``f'(r)`` along ``d`` and the secant ``f(r) / r`` across it.
* ``law="table"``: the same isotropic form with ``f(r)`` from a user table of radial force
  against radial deflection (monotone cubic interpolation, PCHIP; linear beyond the last
  point; a clearance is part of the table).

Gear meshes: the mean mesh stiffness as a function of the mean mesh force ``F`` (along the
line of action), ``k(F)``, from a user table (PCHIP, constant beyond it) or ISO 6336-1's
reduction at low line loads: ``k(F) = k0 (F / (b 100 N/mm))^(1/4)`` below
``F = b 100 N/mm`` (``b``: face width), ``k0`` above. The static mesh deflection solves
``F = k(F) delta``; the operating (tangent) stiffness is
``dF/d delta = k / (1 - delta k'(F))`` (``4/3 k`` on ISO's reduced branch).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.interpolate import PchipInterpolator

from ..errors import ModelError

__all__ = ["EXPONENTS", "MAX_ELEMENTS", "MeshLoadLaw", "RollingLaw", "rolling_record"]

#: Rolling elements of one bearing: a large slewing ring has a few hundred (each element is a
#: row of the law's arrays, so a mistyped count would be refused only by the memory).
MAX_ELEMENTS = 1000

#: Load-deflection exponents of one rolling element: point contact (ball), line contact
#: (roller, Palmgren's 10/9).
EXPONENTS = {"ball": 1.5, "roller": 10.0 / 9.0}

#: ISO 6336-1: the mesh stiffness is reduced below this line load [N/m] (100 N/mm).
ISO_LINE_LOAD = 1e5


@dataclass
class RollingLaw:
    """Radial force-deflection law of a rolling-element bearing (see the module).

    Parameters
    ----------
    law
        ``"elements"``, ``"radial"`` or ``"table"``.
    kind
        ``"ball"`` or ``"roller"`` (the exponent; not for tables).
    stiffness
        ``K_n`` of one element (``elements``) or ``K`` of the bearing (``radial``)
        [N/m^n].
    elements
        Number of rolling elements ``Z`` (``elements``).
    clearance
        Radial clearance ``c`` [m] (``elements`` and ``radial``).
    angle
        Angle of element 0 from the bearing plane's first axis [rad].
    deflection, force
        The table (``table``): radial deflection [m] (from 0, increasing) and force [N]
        (from 0, non-decreasing).

    Examples
    --------
    A 9-ball bearing without clearance pushed 10 um straight towards an element carries
    the Hertz load of that element and its neighbours:

    >>> law = RollingLaw("elements", "ball", stiffness=1e10, elements=9)
    >>> F, K = law.force(np.array([10e-6, 0.0]))
    >>> float(np.round(-F[0], 3))
    649.011
    """

    law: str = "elements"
    kind: str = "ball"
    stiffness: float = 0.0
    elements: int = 0
    clearance: float = 0.0
    angle: float = 0.0
    deflection: np.ndarray | None = None
    force_table: np.ndarray | None = None
    _table: Any = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if self.law not in ("elements", "radial", "table"):
            raise ModelError(f"`law` must be 'elements', 'radial' or 'table', got {self.law!r}")
        if self.law == "table":
            d = np.asarray(self.deflection, dtype=float).ravel()
            f = np.asarray(self.force_table, dtype=float).ravel()
            if d.size < 2 or d.size != f.size:
                raise ModelError(
                    "`deflection` and `force`: a table needs two or more points, equally many"
                )
            if not (np.all(np.isfinite(d)) and np.all(np.isfinite(f))):
                raise ModelError("`deflection` and `force` must be finite")
            if d[0] != 0.0 or f[0] != 0.0 or np.any(np.diff(d) <= 0) or np.any(np.diff(f) < 0):
                raise ModelError(
                    "`deflection` must start at 0 and increase, `force` start at 0 and not "
                    f"decrease; got deflection {d.tolist()}, force {f.tolist()}"
                )
            if not f[-1] > 0.0:
                raise ModelError("`force`: the table carries no load (every force is 0)")
            self.deflection, self.force_table = d, f
            self._table = PchipInterpolator(d, f, extrapolate=False)
            return
        if self.kind not in EXPONENTS:
            raise ModelError(f"`kind` must be one of {sorted(EXPONENTS)}, got {self.kind!r}")
        if not (np.isfinite(self.stiffness) and self.stiffness > 0):
            raise ModelError(f"`stiffness` must be > 0 [N/m^n], got {self.stiffness!r}")
        if not (np.isfinite(self.clearance) and self.clearance >= 0):
            raise ModelError(f"`clearance` must be >= 0 [m], got {self.clearance!r}")
        if self.law == "elements" and (
            isinstance(self.elements, bool) or int(self.elements) != self.elements
            or not 3 <= self.elements <= MAX_ELEMENTS
        ):  # fmt: skip
            raise ModelError(
                f"`elements` must be an integer from 3 to {MAX_ELEMENTS}, got {self.elements!r}"
            )

    @property
    def exponent(self) -> float:
        return EXPONENTS[self.kind]

    def directions(self) -> np.ndarray:
        """Unit vectors of the elements in the bearing plane (``Z x 2``)."""
        psi = self.angle + 2 * np.pi * np.arange(int(self.elements)) / int(self.elements)
        return np.column_stack([np.cos(psi), np.sin(psi)])

    def radial(self, r: float) -> tuple[float, float]:
        """``(f(r), f'(r))`` of the isotropic laws (``radial``, ``table``)."""
        if self.law == "table":
            d, f = self.deflection, self.force_table
            assert d is not None and f is not None
            if r <= d[-1]:
                return float(self._table(r)), float(self._table(r, 1))
            slope = float(self._table(d[-1], 1))
            return float(f[-1] + slope * (r - d[-1])), slope
        n, gap = self.exponent, r - self.clearance
        if gap <= 0:
            return 0.0, 0.0
        return float(self.stiffness * gap**n), float(n * self.stiffness * gap ** (n - 1))

    def force(self, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Force on the inner ring ``F`` (2) and tangent stiffness ``-dF/dd`` (2 x 2) at the
        radial displacement ``d`` (2, bearing-plane axes)."""
        d = np.asarray(d, dtype=float)
        if self.law == "elements":
            E = self.directions()
            gap = E @ d - self.clearance
            on = gap > 0
            n, k = self.exponent, self.stiffness
            Q = np.where(on, k * np.where(on, gap, 0.0) ** n, 0.0)
            kt = np.where(on, n * k * np.where(on, gap, 1.0) ** (n - 1), 0.0)
            return -(E.T @ Q), (E.T * kt) @ E
        r = float(np.hypot(d[0], d[1]))
        f, df = self.radial(r)
        if r == 0.0:
            return np.zeros(2), df * np.eye(2)
        e = d / r
        P = np.outer(e, e)
        return -f * e, df * P + (f / r) * (np.eye(2) - P)

    def in_contact(self, d: np.ndarray) -> int:
        """Elements in contact (``elements``), or 1/0 for the lumped laws."""
        d = np.asarray(d, dtype=float)
        if self.law == "elements":
            return int(np.count_nonzero(self.directions() @ d - self.clearance > 0))
        return int(self.radial(float(np.hypot(d[0], d[1])))[0] > 0)

    def reference_stiffness(self) -> float:
        """A stiffness that stands for the bearing where its tangent vanishes (a clearance):
        the tangent at a 1 um radial deflection past the clearance, all elements loaded alike
        (``elements``: ``Z n K_n delta^(n-1) / 2``), or a table's secant at its end."""
        if self.law == "table":  # its secant at the end: a clearance starts it at zero
            d, f = self.deflection, self.force_table
            assert d is not None and f is not None
            return float(f[-1] / d[-1])
        gap = 1e-6
        kt = self.exponent * self.stiffness * gap ** (self.exponent - 1)
        return kt * (int(self.elements) / 2 if self.law == "elements" else 1.0)


@dataclass
class MeshLoadLaw:
    """Mean mesh stiffness against mean mesh force (see the module).

    ``iso6336``: ``face_width`` [m] with the nominal stiffness ``k0`` [N/m] of the mesh;
    ``table``: ``forces`` [N] (increasing, >= 0) and ``stiffness`` [N/m] (> 0).

    >>> law = MeshLoadLaw("iso6336", face_width=0.02)
    >>> k, kt, delta = law.at(1000.0, 4e8)   # F = 1 kN on b = 20 mm: 50 N/mm
    >>> round(k / 4e8, 6), round(kt / k, 6), round(delta * k / 1000.0, 12)
    (0.840896, 1.333333, 1.0)
    """

    law: str = "table"
    face_width: float = 0.0
    forces: np.ndarray | None = None
    stiffness: np.ndarray | None = None
    _table: Any = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if self.law == "iso6336":
            if not (np.isfinite(self.face_width) and self.face_width > 0):
                raise ModelError(f"`face_width` must be > 0 [m], got {self.face_width!r}")
            return
        if self.law != "table":
            raise ModelError(f"`load_law` must be 'iso6336' or 'table', got {self.law!r}")
        F = np.asarray(self.forces, dtype=float).ravel()
        k = np.asarray(self.stiffness, dtype=float).ravel()
        if F.size < 2 or F.size != k.size:
            raise ModelError(
                "`forces` and `stiffness`: a table needs two or more points, equally many"
            )
        if not (np.all(np.isfinite(F)) and np.all(np.isfinite(k))):
            raise ModelError("`forces` and `stiffness` must be finite")
        if F[0] < 0 or np.any(np.diff(F) <= 0) or np.any(k <= 0):
            raise ModelError(
                "`forces` must be >= 0 and increase, `stiffness` > 0; got forces "
                f"{F.tolist()}, stiffness {k.tolist()}"
            )
        self.forces, self.stiffness = F, k
        self._table = PchipInterpolator(F, k, extrapolate=False)

    def k(self, F: float, k0: float) -> tuple[float, float]:
        """``(k(F), k'(F))`` for a mesh of nominal mean stiffness ``k0``."""
        F = abs(float(F))
        if self.law == "iso6336":
            Fr = self.face_width * ISO_LINE_LOAD
            if F >= Fr:
                return k0, 0.0
            if F <= 0:
                return 0.0, np.inf
            k = k0 * (F / Fr) ** 0.25
            return k, 0.25 * k / F
        forces, stiff = self.forces, self.stiffness
        assert forces is not None and stiff is not None
        if F <= forces[0]:
            return float(stiff[0]), 0.0
        if F >= forces[-1]:
            return float(stiff[-1]), 0.0
        return float(self._table(F)), float(self._table(F, 1))

    def at(self, F: float, k0: float) -> tuple[float, float, float]:
        """At mean mesh force ``F``: secant ``k(F)``, tangent ``dF/d delta`` and the mesh
        deflection ``delta = F / k(F)``."""
        k, dk = self.k(F, k0)
        if k <= 0:
            raise ModelError("the mesh stiffness law gives no stiffness at zero load")
        delta = abs(F) / k
        denom = 1.0 - delta * dk if np.isfinite(dk) else 0.0
        kt = k / denom if denom > 0 else np.inf
        return k, kt, float(np.sign(F) * delta) if F else 0.0

    def force(self, delta: float, k0: float) -> tuple[float, float]:
        """The mean mesh force at mesh deflection ``delta`` (inverse of ``F / k(F)``) and the
        tangent ``dF/d delta``: one monotone scalar equation, solved by bracketing."""
        from scipy.optimize import brentq

        if delta == 0.0:
            k, dk = self.k(0.0, k0)
            return 0.0, (k if np.isfinite(dk) and k > 0 else 0.0)
        s = np.sign(delta)
        d = abs(delta)

        def g(F: float) -> float:
            return F / self.k(F, k0)[0] - d if F > 0 else -d

        hi = max(d * k0, 1e-12)
        for _ in range(200):
            if g(hi) > 0:
                break
            hi *= 2.0
        F = brentq(g, 0.0, hi, xtol=1e-14 * hi, rtol=4 * np.finfo(float).eps, maxiter=500)
        _, kt, _ = self.at(F, k0)
        return float(s * F), float(kt)


def rolling_record(
    law: str,
    kind: str,
    stiffness: float,
    elements: int,
    clearance: float,
    angle: float,
    deflection: Sequence[float] | None,
    force: Sequence[float] | None,
    damping: float,
) -> dict[str, Any]:
    """The law and radial damping of a rolling-element bearing, checked, as the model's
    table of load-dependent joints holds them (``Model.add_rolling_bearing`` names the
    arguments).

    >>> r = rolling_record("radial", "roller", 1.5e9, 0, 0.0, 0.0, None, None, 300.0)
    >>> r["law"].exponent == EXPONENTS["roller"], r["damping"]
    (True, 300.0)
    """
    rolling_law = RollingLaw(
        law=law,
        kind=kind,
        stiffness=float(stiffness),
        elements=elements,
        clearance=float(clearance),
        angle=float(angle),
        deflection=None if deflection is None else np.asarray(deflection, float),
        force_table=None if force is None else np.asarray(force, float),
    )
    if not (np.isfinite(damping) and damping >= 0):
        raise ModelError(f"`damping` must be >= 0 [N s/m], got {damping!r}")
    return dict(law=rolling_law, damping=float(damping))
