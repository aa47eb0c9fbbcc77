"""Campbell diagram: averaged-system modes against speed, order lines and critical speeds."""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..linalg.threads import single_thread_blas
from .modes import (
    DENSE_MODES_LIMIT,
    WHIRL_THRESHOLD,
    averaged_modes,
    mac,
    mode_energy,
    mode_kind,
    planetary_kinds,
    whirl_ratio,
)
from .standstill import STANDSTILL

__all__ = ["STANDSTILL", "CampbellResult", "CriticalSpeed", "campbell", "order_lines"]


@dataclass(frozen=True)
class CriticalSpeed:
    """A crossing of a mode branch with an order line.

    Attributes
    ----------
    order
        Name of the order line (e.g. ``"1x shaft"``, ``"mesh mesh1"``).
    mode
        Branch index (modes sorted by frequency at every speed).
    speed
        Input speed [rad/s] at the crossing (linear interpolation between samples).
    frequency
        Frequency at the crossing [rad/s].
    whirl
        ``"forward"``, ``"backward"``, ``"mixed"`` or ``"none"`` at the crossing.
    kind
        The branch's kind at the crossing (``"lateral forward"``, ``"torsional"``, ...).
    """

    order: str
    mode: int
    speed: float
    frequency: float
    whirl: str
    kind: str = ""


@dataclass
class CampbellResult:
    """Campbell diagram data (see :func:`campbell`).

    Attributes
    ----------
    speeds
        Input speeds [rad/s], shape ``(n_speed,)``.
    frequency, damping_ratio, log_decrement, whirl_ratio
        Per speed and mode branch, shape ``(n_speed, n_modes)``; NaN where a branch has no
        oscillatory mode. ``whirl_ratio`` is +1 forward, -1 backward, 0 no whirl.
    whirl
        Labels from ``whirl_ratio``: ``"forward"``, ``"backward"``, ``"mixed"``, ``"none"``.
    orders
        ``{name: frequency per unit input speed}`` of the order lines.
    critical_speeds
        Crossings of branches with order lines, by speed.
    kind
        Per speed and branch: ``"lateral forward"``, ``"lateral backward"``, ``"lateral"``,
        ``"torsional"``, ``"axial"`` or ``"coupled (...)"`` (:func:`~rheolin.stability.modes.
        mode_kind`), ``""`` where a branch has no mode.
    tracked
        Branches follow each mode across speed by its shape (MAC); else sorted by frequency.
    """

    speeds: np.ndarray
    frequency: np.ndarray
    damping_ratio: np.ndarray
    log_decrement: np.ndarray
    whirl_ratio: np.ndarray
    orders: dict[str, float]
    critical_speeds: list[CriticalSpeed] = field(default_factory=list)
    kind: np.ndarray | None = None
    tracked: bool = False

    @property
    def whirl(self) -> np.ndarray:
        """Whirl labels, shape ``(n_speed, n_modes)``."""
        return np.vectorize(_whirl_label, otypes=[object])(self.whirl_ratio)

    def to_dataset(self) -> Any:
        """The diagram as an ``xarray.Dataset`` (dims ``speed``, ``mode``, ``order``,
        ``critical``), in the files' units (:mod:`rheolin.results.units`): speeds in rad/s
        with ``*_rpm`` beside them, frequencies in Hz.

        >>> import numpy as np
        >>> r = CampbellResult(np.array([1.0, 2.0]), np.ones((2, 1)), np.zeros((2, 1)),
        ...                    np.zeros((2, 1)), np.ones((2, 1)), {"1x s": 1.0})
        >>> ds = r.to_dataset()
        >>> ds["frequency"].dims, ds["order_ratio"].values.tolist(), ds["frequency"].attrs["units"]
        (('speed', 'mode'), [1.0], 'Hz')
        """
        import xarray as xr

        from ..io.units import significant

        crit = self.critical_speeds
        hz = 1.0 / (2 * np.pi)
        rpm = 30 / np.pi
        one = {"units": "1"}
        speed_c = np.array([c.speed for c in crit], float)
        ds = xr.Dataset(
            {
                "frequency": (
                    ("speed", "mode"),
                    self.frequency * hz,
                    {"units": "Hz", "long_name": "damped natural frequency"},
                ),
                "damping_ratio": (("speed", "mode"), self.damping_ratio, one),
                "log_decrement": (("speed", "mode"), self.log_decrement, one),
                "whirl_ratio": (("speed", "mode"), self.whirl_ratio, one),
                "whirl": (("speed", "mode"), self.whirl.astype(str)),
                "order_ratio": (
                    ("order",),
                    np.array(list(self.orders.values()), dtype=float),
                    {"units": "1", "long_name": "order-line frequency per unit input speed"},
                ),
                "critical_speed": (("critical",), speed_c, {"units": "rad/s"}),
                "critical_speed_rpm": (
                    ("critical",),
                    np.array([significant(x) for x in speed_c * rpm], float),
                    {"units": "rpm"},
                ),
                "critical_frequency": (
                    ("critical",),
                    np.array([c.frequency for c in crit], float) * hz,
                    {"units": "Hz"},
                ),
                "critical_order": (("critical",), np.array([c.order for c in crit], dtype=str)),
                "critical_mode": (("critical",), np.array([c.mode for c in crit], dtype=int), one),
                "critical_whirl": (("critical",), np.array([c.whirl for c in crit], dtype=str)),
                "critical_kind": (("critical",), np.array([c.kind for c in crit], dtype=str)),
                "kind": (
                    ("speed", "mode"),
                    (
                        self.kind.astype(str)
                        if self.kind is not None
                        else np.full(self.frequency.shape, "", dtype=str)
                    ),
                ),
            },
            coords={
                "speed": ("speed", self.speeds, {"units": "rad/s"}),
                "speed_rpm": (
                    "speed",
                    np.array([significant(x) for x in self.speeds * rpm], float),
                    {"units": "rpm"},
                ),
                "mode": ("mode", np.arange(self.frequency.shape[1]), one),
                "order": np.array(list(self.orders), dtype=str),
            },
        )
        ds.attrs["title"] = "Campbell diagram of the time-averaged system"
        ds.attrs["branches"] = "tracked by mode shape (MAC)" if self.tracked else "sorted"
        return ds


def _whirl_label(r: float) -> str:
    if not np.isfinite(r) or abs(r) < 1e-3:
        return "none"
    if r >= WHIRL_THRESHOLD:
        return "forward"
    if r <= -WHIRL_THRESHOLD:
        return "backward"
    return "mixed"


def order_lines(model: Any, speed: float = 1.0) -> dict[str, float]:
    """Order lines of a model, as frequency per unit input speed: ``1x`` and ``2x`` of every
    rotating body and the mesh frequency of every gear mesh.

    >>> from rheolin.mechanics import Model
    >>> m = Model()
    >>> m.add_rigid_body("rotor", (0, 0, 0), 1.0, (1.0, 1.0, 1.0))
    >>> order_lines(m)
    {'1x rotor': 1.0, '2x rotor': 2.0}
    """
    plan = model.speed_plan()
    out: dict[str, float] = {}
    planets = {b for s in getattr(model, "planetary", {}).values() for b in s.planets}
    for body, ratio in plan.ratios.items():
        if ratio != 0 and body not in planets:
            out[f"1x {body}"] = float(abs(ratio)) * speed
            out[f"2x {body}"] = 2 * float(abs(ratio)) * speed
    for name, harmonic in zip(model.meshes, plan.mesh, strict=True):
        out[f"mesh {name}"] = float(harmonic * plan.base) * speed
    for name, harmonic in plan.sets.items():  # planetary sets: one mesh frequency each
        out[f"mesh {name}"] = float(harmonic * plan.base) * speed
    return out


def campbell(
    model: Any,
    speeds_rad_s: Any,
    *,
    n_modes: int | None = None,
    method: str = "auto",
    track: bool = True,
    progress: Callable[[int], None] | None = None,
) -> CampbellResult:
    """Campbell diagram of a :class:`~rheolin.mechanics.Model` over input speeds.

    At every speed the model is assembled and the oscillatory modes of the time-averaged
    system ``M_0 q'' + D_0 q' + K_0 q = 0`` (gyroscopic and circulatory terms included) are
    computed; each mode gets its damped frequency, damping ratio, logarithmic decrement,
    whirl direction (:func:`~rheolin.stability.modes.whirl_ratio`) and kind (lateral forward
    or backward, torsional, axial, coupled: by where its kinetic energy sits,
    :func:`~rheolin.stability.modes.mode_kind`). Branches follow each mode from speed to speed
    by the modal assurance criterion of its shape (``track=True``; a forward and a backward
    branch that cross keep their identities), else they are the modes sorted by frequency.
    Crossings of the branches with the order lines (:func:`order_lines`) are the critical
    speeds.

    Parameters
    ----------
    model
        The model.
    speeds_rad_s
        Increasing input speeds [rad/s], >= 0 (0: the modes at standstill).
    n_modes
        Number of lowest modes kept (default: all for small models, 12 for large ones).
    method
        Eigen-solver for the averaged system: ``"auto"``, ``"dense"``, ``"sparse"``.
    progress
        Called with the number of speeds done after each speed.

    Examples
    --------
    A rigid rotor on isotropic bearings: translation modes at ``sqrt(k / m)`` cross the 1x
    line there:

    >>> import numpy as np
    >>> from rheolin.mechanics import Model
    >>> m = Model()
    >>> m.add_rigid_body("rotor", (0, 0, 0), 1.0, (0.1, 0.1, 0.2))
    >>> m.add_bearing("b", "rotor", 0, [1e4] * 5 + [0.0], [1.0] * 5 + [0.0], components=None)
    >>> r = campbell(m, np.linspace(50, 150, 5))
    >>> sorted({round(c.speed, 1) for c in r.critical_speeds if c.order == "1x rotor"})
    [100.0]
    """
    speeds = np.asarray(speeds_rad_s, dtype=float).ravel()
    if (
        speeds.size < 1
        or not np.all(np.isfinite(speeds))
        or np.any(speeds < 0)
        or np.any(np.diff(speeds) <= 0)
    ):
        raise ValueError("`speeds_rad_s` must be >= 0 and strictly increasing [rad/s]")
    rows = []
    template = model.speed_template()  # assembled once, rescaled at every speed
    axes = {b: model.bodies[b].axis for b in model.bodies}
    for W in speeds:
        # standstill: the periodic system needs a base frequency > 0; at 1e-9 rad/s the speed
        # terms (gyroscopic, centrifugal) are ~1e-9 of their value at 1 rad/s: the W = 0 modes
        a = template.assemble(float(W) if W > 0 else STANDSTILL)
        small = method == "dense" or (method == "auto" and 2 * a.system.n <= DENSE_MODES_LIMIT)
        # a few hundred rows: BLAS threads cost more than they bring (linalg.threads)
        with single_thread_blas() if small else contextlib.nullcontext():
            modes = averaged_modes(a.system, n_modes, method=method)
            ratio = whirl_ratio(modes.shapes, a.dof_labels, axes, a.plan.spin)
            energy = mode_energy(modes.shapes, a.dof_labels, axes, a.system.M[0])
        kinds = planetary_kinds(mode_kind(energy, ratio), modes.shapes, model, a)
        rows.append((modes, ratio, kinds))
        if progress is not None:
            progress(len(rows))
    width = max(m.eigenvalues.size for m, _, _ in rows)
    if n_modes is not None:
        width = min(width, int(n_modes))
    shape = (speeds.size, width)
    freq, zeta, delta, whirl = (np.full(shape, np.nan) for _ in range(4))
    kind = np.full(shape, "", dtype=object)
    picks = _track([m for m, _, _ in rows], width) if track else None
    for i, (m, r, k) in enumerate(rows):
        if picks is None:
            sel = np.arange(min(m.eigenvalues.size, width))
            cols = sel
        else:
            cols = np.flatnonzero(picks[i] >= 0)
            sel = picks[i][cols]
        freq[i, cols] = m.frequency[sel]
        zeta[i, cols] = m.damping_ratio[sel]
        delta[i, cols] = m.log_decrement[sel]
        whirl[i, cols] = r[sel]
        kind[i, cols] = k[sel]
    orders = order_lines(model)
    result = CampbellResult(
        speeds, freq, zeta, delta, whirl, orders, kind=kind, tracked=picks is not None
    )
    result.critical_speeds = _crossings(result)
    return result


#: Tracking: the weight of the relative frequency change against ``1 - MAC`` in the cost of
#: pairing a mode with a branch (shapes decide; frequency breaks ties of degenerate pairs).
FREQUENCY_WEIGHT = 0.2


def _track(modes: list[Any], width: int) -> list[np.ndarray]:
    """For every speed, the mode index each branch takes (-1: none): the first speed's modes
    by frequency, then each next speed's paired with the branches by the least total
    ``1 - MAC`` against the branch's last shape (plus :data:`FREQUENCY_WEIGHT` x the relative
    frequency change; Hungarian assignment). Modes left over fill free branches."""
    from scipy.optimize import linear_sum_assignment

    first = modes[0]
    k0 = min(first.eigenvalues.size, width)
    pick = np.full(width, -1)
    pick[:k0] = np.arange(k0)
    out = [pick]
    shapes = np.full((first.shapes.shape[0], width), np.nan + 0j)
    shapes[:, :k0] = first.shapes[:, :k0]
    freqs = np.full(width, np.nan)
    freqs[:k0] = first.frequency[:k0]
    for m in modes[1:]:
        live = np.flatnonzero(np.isfinite(freqs))
        k = m.eigenvalues.size
        pick = np.full(width, -1)
        if live.size and k:
            cost = 1.0 - mac(shapes[:, live], m.shapes)
            scale = np.maximum(np.abs(freqs[live])[:, None], np.abs(m.frequency)[None, :])
            cost += (
                FREQUENCY_WEIGHT
                * np.abs(freqs[live][:, None] - m.frequency[None, :])
                / (np.maximum(scale, 1e-300))
            )
            r, c = linear_sum_assignment(cost)
            pick[live[r]] = c
        taken = set(pick[pick >= 0].tolist())
        free = [b for b in range(width) if pick[b] < 0]
        for j in sorted(set(range(k)) - taken, key=lambda j: m.frequency[j]):
            if not free:
                break
            pick[free.pop(0)] = j
        for b in np.flatnonzero(pick >= 0):
            shapes[:, b] = m.shapes[:, pick[b]]
            freqs[b] = m.frequency[pick[b]]
        out.append(pick)
    return out


def _crossings(r: CampbellResult) -> list[CriticalSpeed]:
    out: list[CriticalSpeed] = []
    W = r.speeds
    for name, ratio in r.orders.items():
        for mode in range(r.frequency.shape[1]):
            g = r.frequency[:, mode] - ratio * W
            for i in range(W.size - 1):
                if not (np.isfinite(g[i]) and np.isfinite(g[i + 1])):
                    continue
                if g[i] == 0 or g[i] * g[i + 1] < 0:
                    t = 0.0 if g[i] == 0 else g[i] / (g[i] - g[i + 1])
                    ws = W[i] + t * (W[i + 1] - W[i])
                    wr = r.whirl_ratio[i, mode] + t * (
                        r.whirl_ratio[i + 1, mode] - r.whirl_ratio[i, mode]
                    )
                    kind = ""
                    if r.kind is not None:
                        kind = str(r.kind[i + 1, mode] if t > 0.5 else r.kind[i, mode])
                    out.append(
                        CriticalSpeed(
                            name, mode, float(ws), float(ratio * ws), _whirl_label(float(wr)), kind
                        )
                    )
    return sorted(out, key=lambda c: (c.speed, c.order))
