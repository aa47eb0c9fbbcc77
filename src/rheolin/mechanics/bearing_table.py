"""Speed-dependent bearing and seal coefficients: :class:`SpeedTable`.

Journal bearings and seals have stiffness, damping and added-mass coefficients that change
with the journal speed, usually given as a table over a few speeds (full 2x2 cross-coupled
or larger). A :class:`SpeedTable` holds the 6x6 matrices at each tabulated speed and
interpolates every coefficient with a SciPy interpolator:

* ``"cubic"`` (default): ``scipy.interpolate.make_interp_spline`` of degree ``min(3, n - 1)``
  (not-a-knot cubic spline through every point);
* ``"linear"``, ``"pchip"`` (``PchipInterpolator``, monotone), ``"akima"``
  (``Akima1DInterpolator``);
* ``"smoothing"``: ``scipy.interpolate.UnivariateSpline`` with its default smoothing, or
  ``interp1d`` of degree ``n - 1`` for 2 or 3 speeds: what ROSS (``ross.BearingElement``)
  uses, so that an imported ROSS rotor gives ROSS's coefficients between the table speeds.

Outside the table the end values are held (``extrapolate=False``, the default) or the
interpolant is extrapolated. The speed is that of the bearing's ``body`` [rad/s].
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import interpolate

from ..errors import ModelError

__all__ = ["INTERPOLATIONS", "SpeedTable"]

#: The interpolation methods of :class:`SpeedTable`.
INTERPOLATIONS = ("cubic", "linear", "pchip", "akima", "smoothing")


def _smoothing(x: np.ndarray, y: np.ndarray) -> Callable[[float], np.ndarray]:
    """Per-coefficient ``UnivariateSpline`` (ROSS's choice), ``interp1d`` for 2-3 points."""
    import warnings

    fns: list[Any] = []
    for col in y.T:
        if not np.any(col != col[0]):
            fns.append(float(col[0]))
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                fns.append(interpolate.UnivariateSpline(x, col))
        except Exception:  # too few points for a cubic smoothing spline
            fns.append(interpolate.interp1d(x, col, kind=len(x) - 1, fill_value="extrapolate"))

    def evaluate(s: float) -> np.ndarray:
        return np.array([fn if isinstance(fn, float) else float(fn(s)) for fn in fns])

    return evaluate


@dataclass
class SpeedTable:
    """Bearing coefficients tabulated over speed.

    Parameters
    ----------
    speeds
        Strictly increasing speeds [rad/s] of the bearing's body.
    K, D, M
        Stiffness, damping and added mass at each speed, shape ``(n_speeds, 6, 6)`` (see
        :func:`~rheolin.mechanics.joints.expand_matrix` for one speed's matrix).
    interpolation
        One of :data:`INTERPOLATIONS`.
    extrapolate
        Extrapolate outside ``speeds`` instead of holding the end values.

    Examples
    --------
    >>> import numpy as np
    >>> K = np.zeros((3, 6, 6)); K[:, 0, 0] = [1e7, 2e7, 4e7]
    >>> t = SpeedTable([100.0, 200.0, 400.0], K, np.zeros((3, 6, 6)), np.zeros((3, 6, 6)),
    ...                interpolation="linear")
    >>> float(t.at(300.0)[0][0, 0]), float(t.at(1000.0)[0][0, 0])
    (30000000.0, 40000000.0)
    """

    speeds: Any
    K: Any
    D: Any
    M: Any
    interpolation: str = "cubic"
    extrapolate: bool = False
    _fn: Callable[[float], np.ndarray] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        x = np.asarray(self.speeds, dtype=float).ravel()
        if x.size < 1 or not np.all(np.isfinite(x)) or np.any(np.diff(x) <= 0) or x[0] < 0:
            raise ModelError(
                f"`speeds` must be finite, >= 0 and strictly increasing [rad/s], got {x.tolist()}"
            )
        if self.interpolation not in INTERPOLATIONS:
            raise ModelError(
                f"`interpolation` must be one of {list(INTERPOLATIONS)}, got {self.interpolation!r}"
            )
        mats = []
        for name in ("K", "D", "M"):
            a = np.asarray(getattr(self, name), dtype=float)
            if a.shape != (x.size, 6, 6) or not np.all(np.isfinite(a)):
                raise ModelError(
                    f"`{name}` table must be finite with shape ({x.size}, 6, 6), got {a.shape}"
                )
            mats.append(a)
        self.speeds = x
        self.K, self.D, self.M = mats
        y = np.concatenate([a.reshape(x.size, 36) for a in mats], axis=1)
        self._fn = self._interpolant(x, y)

    def _interpolant(self, x: np.ndarray, y: np.ndarray) -> Callable[[float], np.ndarray]:
        if x.size == 1:
            return lambda s: y[0]
        kind = self.interpolation
        if kind == "smoothing":
            return _smoothing(x, y)
        if kind in ("pchip", "akima") and x.size < 3:
            kind = "linear"
        if kind == "pchip":
            return interpolate.PchipInterpolator(x, y, axis=0, extrapolate=True)
        if kind == "akima":
            return interpolate.Akima1DInterpolator(x, y, axis=0, extrapolate=True)
        k = 1 if kind == "linear" else min(3, x.size - 1)
        return interpolate.make_interp_spline(x, y, k=k, axis=0)

    def at(self, speed: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(K, D, M)`` (6x6 each) at ``speed`` [rad/s]."""
        s = float(speed)
        if not self.extrapolate:
            s = min(max(s, float(self.speeds[0])), float(self.speeds[-1]))
        v = np.asarray(self._fn(s), dtype=float).reshape(3, 6, 6)
        return v[0], v[1], v[2]
