"""Stability map: the largest Floquet real part of the full periodic system against speed."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import brentq

from ..floquet import FloquetResult, floquet
from ..harmonics import HarmonicSet, as_harmonic_set
from ..mechanics.assembly import assemble_coefficients
from ..solvers.solve import stability_harmonics
from ..system import PeriodicSystem

__all__ = ["StabilityMap", "UnstableRange", "mechanism", "stability_map"]

_EPS = float(np.finfo(float).eps)
ROTATING_DAMPING = "rotating damping"
CIRCULATORY = "circulatory forces (time-invariant)"
MESH = "parametric mesh resonance"
ASYMMETRY = "asymmetric shaft band"
COMBINED = "combined parametric excitation"


@dataclass(frozen=True)
class UnstableRange:
    """A contiguous unstable speed range.

    Attributes
    ----------
    lower, upper
        Bounds [rad/s], refined by bisection between the bracketing samples.
    lower_open, upper_open
        True when the range reaches the end of the sweep (the bound is the sweep's end).
    max_real
        Largest Floquet real part found in the range [1/s].
    mechanism
        ``"rotating damping"``, ``"circulatory forces (time-invariant)"``,
        ``"parametric mesh resonance"``, ``"asymmetric shaft band"``,
        ``"combined parametric excitation"``; or ``"unidentified"``.
    """

    lower: float
    upper: float
    lower_open: bool
    upper_open: bool
    max_real: float
    mechanism: str


@dataclass
class StabilityMap:
    """Floquet stability against input speed (see :func:`stability_map`).

    Attributes
    ----------
    speeds
        Input speeds [rad/s].
    max_real
        Largest Floquet real part per speed [1/s].
    tol
        Tolerance of the decisive exponent per speed [1/s].
    stable, marginal, converged
        Per speed (see :class:`~rheolin.FloquetResult`).
    frequency
        ``|Im|`` of the dominant (folded) exponent per speed [rad/s].
    ranges
        The unstable speed ranges.
    """

    speeds: np.ndarray
    max_real: np.ndarray
    tol: np.ndarray
    stable: np.ndarray
    marginal: np.ndarray
    converged: np.ndarray
    frequency: np.ndarray
    ranges: list[UnstableRange] = field(default_factory=list)

    @property
    def all_stable(self) -> bool:
        """True when every speed of the sweep is stable."""
        return bool(np.all(self.stable))

    def to_dataset(self) -> Any:
        """The map as an ``xarray.Dataset`` (dims ``speed`` and ``range``).

        >>> import numpy as np
        >>> m = StabilityMap(np.array([1.0]), np.array([-0.1]), np.array([1e-9]),
        ...                  np.array([True]), np.array([False]), np.array([True]),
        ...                  np.array([3.0]))
        >>> m.to_dataset()["max_real"].values.tolist()
        [-0.1]
        """
        import xarray as xr

        rg = self.ranges
        ds = xr.Dataset(
            {
                "max_real": (("speed",), self.max_real),
                "tol": (("speed",), self.tol),
                "stable": (("speed",), self.stable.astype(bool)),
                "marginal": (("speed",), self.marginal.astype(bool)),
                "converged": (("speed",), self.converged.astype(bool)),
                "frequency": (("speed",), self.frequency),
                "range_lower": (("range",), np.array([r.lower for r in rg], float)),
                "range_upper": (("range",), np.array([r.upper for r in rg], float)),
                "range_lower_open": (("range",), np.array([r.lower_open for r in rg], bool)),
                "range_upper_open": (("range",), np.array([r.upper_open for r in rg], bool)),
                "range_max_real": (("range",), np.array([r.max_real for r in rg], float)),
                "range_mechanism": (("range",), np.array([r.mechanism for r in rg], str)),
            },
            coords={"speed": self.speeds},
        )
        ds["speed"].attrs["units"] = "rad/s"
        ds["max_real"].attrs.update(units="1/s", long_name="largest Floquet real part")
        ds.attrs["title"] = "Floquet stability map"
        return ds


def _harmonics(system: PeriodicSystem, harmonics: Any) -> HarmonicSet:
    if harmonics is None:
        return stability_harmonics(system)
    if callable(harmonics):
        return as_harmonic_set(harmonics(system))
    return as_harmonic_set(harmonics)


def stability_map(
    model: Any,
    speeds_rad_s: Any,
    *,
    harmonics: Any = None,
    method: str = "auto",
    refine: float = 1e-8,
    identify: bool = True,
) -> StabilityMap:
    """Largest Floquet real part of a :class:`~rheolin.mechanics.Model` against speed.

    At every speed the full periodic system is assembled and :func:`rheolin.floquet` decides
    stability (balanced Hill pencil, per-exponent tolerances). Contiguous unstable samples
    form an :class:`UnstableRange`; its bounds are refined (Brent's method on the margin
    ``max_real - tol`` between the bracketing samples) to a relative precision ``refine``,
    and its mechanism is identified at its worst sample (:func:`mechanism`).

    Parameters
    ----------
    model
        The model.
    speeds_rad_s
        Increasing input speeds [rad/s].
    harmonics
        Hill truncation: None (``rheolin.solvers.solve.stability_harmonics`` per speed), a
        harmonic set / int, or ``callable(system) -> harmonic set``.
    method
        Floquet method: ``"auto"``, ``"dense"`` or ``"sparse"``.
    refine
        Relative precision of the range bounds (0: the bounds are the first/last unstable
        samples).
    identify
        Identify the mechanism of each range (a few more Floquet evaluations per range).

    Examples
    --------
    A rigid rotor on a spring fixed in its own axes (``k_x != k_y``): unstable between the
    two critical speeds ``sqrt(k_x / m) = 100`` and ``sqrt(k_y / m) = 110`` rad/s:

    >>> import numpy as np
    >>> from rheolin.mechanics import Model
    >>> m = Model()
    >>> m.add_rigid_body("r", (0, 0, 0), 1.0, (1.0, 1.0, 1.0))
    >>> m.add_bearing("s", "r", 0, [1e4, 1.21e4], components=("ux", "uy"), frame="r")
    >>> m.add_bearing("g", "r", 0, 1e4, 1.0, components=("uz", "phix", "phiy", "phiz"))
    >>> smap = stability_map(m, np.linspace(90, 120, 7))
    >>> r = smap.ranges[0]
    >>> round(r.lower, 3), round(r.upper, 3), r.mechanism
    (100.0, 110.0, 'asymmetric shaft band')
    """
    speeds = np.asarray(speeds_rad_s, dtype=float).ravel()
    if speeds.size < 1 or np.any(speeds <= 0) or np.any(np.diff(speeds) <= 0):
        raise ValueError("`speeds_rad_s` must be positive and strictly increasing [rad/s]")

    def evaluate(W: float) -> tuple[Any, HarmonicSet, FloquetResult]:
        a = model.assemble(float(W))
        H = _harmonics(a.system, harmonics)
        return a, H, floquet(a.system, H, method=method)

    results = [evaluate(W)[2] for W in speeds]
    smap = StabilityMap(
        speeds=speeds,
        max_real=np.array([r.max_real for r in results]),
        tol=np.array([r.tolerances[0] if r.tolerances.size else r.tol for r in results]),
        stable=np.array([r.stable for r in results]),
        marginal=np.array([r.marginal for r in results]),
        converged=np.array([r.converged for r in results]),
        frequency=np.array([abs(r.dominant.imag) for r in results]),
    )
    unstable = ~smap.stable
    i = 0
    while i < speeds.size:
        if not unstable[i]:
            i += 1
            continue
        j = i
        while j + 1 < speeds.size and unstable[j + 1]:
            j += 1
        lo, hi = speeds[i], speeds[j]
        if i > 0:
            lo = _edge(lambda W: _margin(evaluate(W)[2]), speeds[i - 1], speeds[i], refine)
        if j < speeds.size - 1:
            hi = _edge(lambda W: _margin(evaluate(W)[2]), speeds[j], speeds[j + 1], refine)
        worst = i + int(np.argmax(smap.max_real[i : j + 1]))
        mech = "unidentified"
        if identify:
            a, H, _ = evaluate(speeds[worst])
            mech = mechanism(model, a, H, method=method)
        smap.ranges.append(
            UnstableRange(
                float(lo),
                float(hi),
                i == 0,
                j == speeds.size - 1,
                float(smap.max_real[i : j + 1].max()),
                mech,
            )
        )
        i = j + 1
    return smap


def _margin(res: FloquetResult) -> float:
    """Positive exactly when unstable: the largest ``Re - tol`` over the exponents, or (when
    stable) ``min(max_real, 0) - tol`` of the dominant exponent; continuous across a
    transversal crossing of the axis."""
    if not res.stable:
        return float(np.max(res.exponents.real - res.tolerances))
    return min(res.max_real, 0.0) - float(res.tolerances[0] if res.tolerances.size else res.tol)


def _edge(margin: Any, stable_side: float, unstable_side: float, rtol: float) -> float:
    """Speed where ``margin`` changes sign between the two samples (Brent's method)."""
    if rtol <= 0:
        return unstable_side
    return float(
        brentq(margin, stable_side, unstable_side, xtol=rtol * abs(unstable_side), rtol=4 * _EPS)
    )


def _has_rotating_damping(model: Any) -> bool:
    for b in model.bodies.values():
        mat = b.data.get("material")
        if b.kind == "shaft" and mat is not None and mat.damping_beta > 0:
            return True
    return any(j["frame"] is not None and np.any(j["D"]) for j in model.joints.values())


def _split(
    system: PeriodicSystem, mesh_parts: dict[str, dict[int, Any]]
) -> tuple[PeriodicSystem, PeriodicSystem]:
    """``(mesh variation only, everything but the mesh variation)`` on the averaged system."""

    def build(keep_mesh: bool, keep_rest: bool) -> PeriodicSystem:
        tables = {}
        for name in ("M", "D", "K"):
            full = getattr(system, name)
            mesh = mesh_parts[name]
            out = {}
            for k, x in full.items():
                if k == 0:
                    out[k] = x
                    continue
                mk = mesh.get(k)
                rest = x if mk is None else x - mk
                part = (mk if keep_mesh and mk is not None else 0) + (rest if keep_rest else 0)
                if not isinstance(part, int) and abs(part).max() > 0:
                    out[k] = part
            tables[name] = out or None
        return PeriodicSystem(system.omega, M=tables["M"], D=tables["D"], K=tables["K"])

    return build(True, False), build(False, True)


def mechanism(model: Any, assembled: Any, harmonics: Any, *, method: str = "auto") -> str:
    """Name the mechanism of an instability of an assembled model.

    * the time-averaged system is already unstable: ``"rotating damping"`` when the model
      has rotating damping (shaft material damping, damping in a body frame), otherwise
      ``"circulatory forces (time-invariant)"``;
    * only the gear-mesh variation kept (on the averaged system) is unstable:
      ``"parametric mesh resonance"``;
    * everything but the mesh variation (rotating asymmetry at 2x) is unstable:
      ``"asymmetric shaft band"``;
    * neither alone, the full system is: ``"combined parametric excitation"``.
    """
    system = assembled.system
    avg = PeriodicSystem(
        system.omega,
        M={0: system.M[0]} if 0 in system.M else None,
        D={0: system.D[0]} if 0 in system.D else None,
        K={0: system.K[0]} if 0 in system.K else None,
    )
    if not floquet(avg, [0], method=method).stable:
        return ROTATING_DAMPING if _has_rotating_damping(model) else CIRCULATORY
    terms = [t for t, _, _ in assembled.meshes.values()]
    Mm, Dm, Km, _ = assemble_coefficients(terms, system.n) if terms else ({}, {}, {}, {})
    parts = {
        name: {k: v for k, v in table.items() if k != 0}
        for name, table in (("M", Mm), ("D", Dm), ("K", Km))
    }
    mesh_only, rest = _split(system, parts)
    if any(parts.values()) and not mesh_only.time_invariant:
        if not floquet(mesh_only, harmonics, method=method).stable:
            return MESH
    if not rest.time_invariant and not floquet(rest, harmonics, method=method).stable:
        return ASYMMETRY
    return COMBINED
