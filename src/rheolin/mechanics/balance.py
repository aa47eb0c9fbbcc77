"""Permissible residual unbalance from an ISO 21940-11 balance quality grade.

A grade ``G`` is the product ``e_per W`` [mm/s] of the permissible specific unbalance
(centre-of-mass eccentricity) ``e_per`` and the maximum service angular speed ``W``; the
permissible residual unbalance of a rotor of mass ``m`` is ``U_per = m e_per = m G / W``
(in the standard's units ``U_per [g mm] = 9549 G [mm/s] m [kg] / n [rpm]``). It is the whole
rotor's: sharing it between correction planes (by the bearing loads, ISO 21940-11 §7) is the
engineer's choice, and the result goes into ``add_disk(..., unbalance=...)``.

>>> round(iso21940_unbalance("G6.3", 100.0, 3000 * 3.141592653589793 / 30) * 1e6)  # g mm
2005
"""

from __future__ import annotations

import math
import re

from ..errors import ModelError

__all__ = ["GRADES", "iso21940_unbalance"]

#: The grades ISO 21940-11 lists [mm/s] (G 0.4 for gyroscopes ... G 4000 for marine engines).
GRADES = (0.4, 1.0, 2.5, 6.3, 16.0, 40.0, 100.0, 250.0, 630.0, 1600.0, 4000.0)


def _grade(value: str | float) -> float:
    if isinstance(value, str):
        m = re.fullmatch(r"\s*[Gg]\s*([0-9.]+)\s*", value)
        if m is None:
            raise ModelError(f"balance grade: write it like 'G2.5', got {value!r}")
        g = float(m.group(1))
    else:
        g = float(value)
    if not any(math.isclose(g, x, rel_tol=1e-9) for x in GRADES):
        listed = ", ".join(f"G{x:g}" for x in GRADES)
        raise ModelError(f"balance grade: G{g:g} is not an ISO 21940-11 grade ({listed})")
    return g


def iso21940_unbalance(grade: str | float, mass: float, speed: float) -> float:
    """``U_per = m G / W`` [kg m] for a rotor of ``mass`` [kg] at its maximum service speed
    ``speed`` [rad/s] and balance quality ``grade`` (``"G2.5"`` or 2.5, in mm/s)."""
    g = _grade(grade) * 1e-3  # mm/s -> m/s
    m, w = float(mass), float(speed)
    if not (math.isfinite(m) and m > 0):
        raise ModelError(f"`mass` must be a positive rotor mass [kg], got {mass!r}")
    if not (math.isfinite(w) and w > 0):
        raise ModelError(f"`speed` must be the maximum service speed > 0 [rad/s], got {speed!r}")
    return m * g / w
