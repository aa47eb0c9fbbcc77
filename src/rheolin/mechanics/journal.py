"""Plain journal bearings by the short-bearing theory (Ocvirk): stiffness and damping from
geometry, oil and load.

For a bearing of diameter ``D = 2 R``, length ``L``, radial clearance ``c``, oil viscosity
``eta``, journal speed ``W`` and static load ``F``, the short-bearing solution of Reynolds'
equation (pressure parabolic across the length, the film cavitated where it would be
negative: the half-Sommerfeld condition) gives the eccentricity ratio ``e`` from

    F = eta W R L^3 / (4 c^2) * e / (1 - e^2)^2 * sqrt(16 e^2 + pi^2 (1 - e^2))

and, with ``h0 = (pi^2 (1 - e^2) + 16 e^2)^(-3/2)``, the coefficients ``K = (F / c) a``,
``C = (F / (c W)) b`` (Friswell et al., *Dynamics of Rotating Machines*, 2010, sec. 5.5)::

    a_xx = 4 h0 (pi^2 (2 - e^2) + 16 e^2)
    a_xy = h0 pi (pi^2 (1 - e^2)^2 - 16 e^4) / (e sqrt(1 - e^2))
    a_yx = -h0 pi (pi^2 (1 - e^2) (1 + 2 e^2) + 32 e^2 (1 + e^2)) / (e sqrt(1 - e^2))
    a_yy = 4 h0 (pi^2 (1 + 2 e^2) + 32 e^2 (1 + e^2) / (1 - e^2))
    b_xx = 2 pi h0 sqrt(1 - e^2) (pi^2 (1 + 2 e^2) - 16 e^2) / e
    b_xy = b_yx = -8 h0 (pi^2 (1 + 2 e^2) - 16 e^2)
    b_yy = 2 pi h0 (pi^2 (1 - e^2)^2 + 48 e^2) / (e sqrt(1 - e^2))

in axes where the static load on the journal points along ``-y`` and the journal turns
positively about ``z = x cross y``. Valid for short bearings (``L / D`` up to about 0.5) in
laminar flow; the film carries the load only while the journal turns (``W > 0``).

>>> K, C, e = short_journal_bearing(0.1, 0.03, 1e-4, 0.1, 525.0, 1500 * np.pi / 30)
>>> round(e, 4), np.round(K / 1e6, 2).tolist()   # Friswell et al., Example 5.5.1
(0.2663, [[12.81, 16.39], [-25.06, 8.82]])
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.optimize import brentq

from ..errors import ModelError

__all__ = ["journal_bearing_table", "short_journal_bearing"]

#: Above this eccentricity ratio the film is refused as too thin to carry the load (metal
#: contact, and the linearization far from its validity).
MAX_ECCENTRICITY = 0.95

#: Above this length-to-diameter ratio the short-bearing theory overestimates the film force
#: (end leakage is less than it assumes): a warning, not a refusal.
SHORT_LD = 0.5


def _load_factor(e: float) -> float:
    return e / (1 - e * e) ** 2 * np.sqrt(16 * e * e + np.pi**2 * (1 - e * e))


def short_journal_bearing(
    diameter: float,
    length: float,
    clearance: float,
    viscosity: float,
    load: float,
    speed: float,
) -> tuple[np.ndarray, np.ndarray, float]:
    """``(K, C, e)``: 2 x 2 stiffness [N/m] and damping [N s/m] and the eccentricity ratio of
    a plain journal bearing at journal ``speed`` [rad/s, > 0] under a static ``load`` [N]
    (axes of the module docstring: load along ``-y``, rotation positive about ``z``)."""
    values = {
        "diameter": diameter,
        "length": length,
        "clearance": clearance,
        "viscosity": viscosity,
        "load": load,
        "speed": speed,
    }
    for name, v in values.items():
        if not (np.isfinite(v) and v > 0):
            raise ModelError(f"journal bearing `{name}` must be a finite number > 0, got {v!r}")
    if clearance >= diameter / 2:
        raise ModelError("journal bearing `clearance` must be much smaller than the radius")
    R = diameter / 2
    scale = viscosity * speed * R * length**3 / (4 * clearance**2)
    target = load / scale
    if _load_factor(MAX_ECCENTRICITY) < target:
        raise ModelError(
            f"journal bearing: the film cannot carry {load:g} N at {speed:g} rad/s: its "
            f"eccentricity ratio would exceed {MAX_ECCENTRICITY} (a film thinner than "
            f"{1 - MAX_ECCENTRICITY:g} of the clearance): more speed, viscosity or length, "
            "or less clearance"
        )
    e = brentq(lambda x: _load_factor(x) - target, 1e-15, MAX_ECCENTRICITY, xtol=1e-15,
               rtol=1e-15)  # fmt: skip
    pi2, e2 = np.pi**2, e * e
    h0 = 1.0 / (pi2 * (1 - e2) + 16 * e2) ** 1.5
    root = np.sqrt(1 - e2)
    a = h0 * np.array(
        [
            [
                4 * (pi2 * (2 - e2) + 16 * e2),
                np.pi * (pi2 * (1 - e2) ** 2 - 16 * e2 * e2) / (e * root),
            ],
            [
                -np.pi * (pi2 * (1 - e2) * (1 + 2 * e2) + 32 * e2 * (1 + e2)) / (e * root),
                4 * (pi2 * (1 + 2 * e2) + 32 * e2 * (1 + e2) / (1 - e2)),
            ],
        ]
    )
    bxy = -8 * (pi2 * (1 + 2 * e2) - 16 * e2)
    b = h0 * np.array(
        [
            [2 * np.pi * root * (pi2 * (1 + 2 * e2) - 16 * e2) / e, bxy],
            [bxy, 2 * np.pi * (pi2 * (1 - e2) ** 2 + 48 * e2) / (e * root)],
        ]
    )
    return load / clearance * a, load / (clearance * speed) * b, float(e)


def journal_bearing_table(
    diameter: float,
    length: float,
    clearance: float,
    viscosity: float,
    load: float,
    speeds: Sequence[float],
    *,
    axis: Sequence[float] = (0.0, 0.0, 1.0),
    load_direction: Sequence[float] = (0.0, -1.0, 0.0),
    rotation: int = 1,
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Stiffness and damping (3 x 3, global translations ``ux uy uz``) of a plain journal
    bearing at each journal speed of ``speeds`` [rad/s], for
    ``Model.add_bearing(..., stiffness=K, damping=C, speeds=speeds, components=["ux", "uy",
    "uz"])``.

    ``axis`` is the shaft's axis, ``load_direction`` the direction of the static load on the
    journal (default: gravity, ``-y``; projected onto the bearing's plane) and ``rotation``
    the sense the journal turns about ``axis`` (+1, or -1 for a counter-rotating shaft).

    >>> Ks, Cs = journal_bearing_table(0.1, 0.03, 1e-4, 0.1, 525.0, [157.08])
    >>> np.round(Ks[0][:2, :2] / 1e6, 2).tolist()
    [[12.81, 16.39], [-25.06, 8.82]]
    """
    e = np.asarray(axis, dtype=float)
    e = e / np.linalg.norm(e)
    d = np.asarray(load_direction, dtype=float)
    d = d - (d @ e) * e
    if np.linalg.norm(d) < 1e-9:
        raise ModelError("journal bearing `load_direction` must not be along the shaft axis")
    if rotation not in (1, -1):
        raise ModelError(f"journal bearing `rotation` must be +1 or -1, got {rotation!r}")
    if length / diameter > SHORT_LD:
        import warnings

        warnings.warn(
            f"journal bearing L/D = {length / diameter:.2f} > {SHORT_LD}: the short-bearing "
            "theory overestimates its film forces",
            UserWarning,
            stacklevel=2,
        )
    y = -d / np.linalg.norm(d)  # the film pushes the journal against the load
    x = np.cross(y, e)  # (x, y, e) right-handed
    S = np.diag([float(rotation), 1.0])  # a journal turning the other way: x mirrored
    B = np.column_stack([x, y])
    Ks, Cs = [], []
    for w in speeds:
        K2, C2, _ = short_journal_bearing(diameter, length, clearance, viscosity, load, float(w))
        Ks.append(B @ (S @ K2 @ S) @ B.T)
        Cs.append(B @ (S @ C2 @ S) @ B.T)
    return Ks, Cs
