"""Stability map: the largest Floquet real part of the full periodic system against speed."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..floquet import FloquetResult, floquet
from .mechanism import (
    ASYMMETRY,
    CIRCULATORY,
    COMBINED,
    MESH,
    ROTATING_DAMPING,
    UNIDENTIFIED,
    Mechanism,
)
from .mechanism import identify as _identify
from .ranges import edge_between, states, unstable_runs
from .standstill import STANDSTILL_NOTE
from .verdicts import Verdicts, continued_verdicts, in_parallel

__all__ = [
    "StabilityMap",
    "UnstableRange",
    "map_from_results",
    "mechanism",
    "stability_map",
]

__categories__ = (ROTATING_DAMPING, CIRCULATORY, MESH, ASYMMETRY, COMBINED, UNIDENTIFIED)


@dataclass(frozen=True)
class UnstableRange:
    """A contiguous unstable speed range.

    Attributes
    ----------
    lower, upper
        Bounds [rad/s], refined between the bracketing samples where every evaluation is a
        decided verdict (:mod:`rheolin.stability.ranges`).
    lower_open, upper_open
        True when the range reaches the end of the sweep (the bound is the sweep's end).
    max_real
        Largest Floquet real part found in the range [1/s].
    mechanism
        ``"rotating damping"``, ``"circulatory forces (time-invariant)"``,
        ``"parametric mesh resonance"``, ``"asymmetric shaft band"``,
        ``"combined parametric excitation"``; or ``"unidentified"``.
    detail
        The :class:`~rheolin.stability.mechanism.Mechanism` found at the worst sample (the
        generators, principal/secondary/combination, the frequency relation), or None.
    lower_uncertainty, upper_uncertainty
        How far each bound may be from the true edge [rad/s]: the edge lies between a speed
        decided stable and one decided unstable, at most this far from the bound (NaN for an
        open end).
    """

    lower: float
    upper: float
    lower_open: bool
    upper_open: bool
    max_real: float
    mechanism: str
    detail: Mechanism | None = None
    lower_uncertainty: float = float("nan")
    upper_uncertainty: float = float("nan")

    @property
    def label(self) -> str:
        """The mechanism in one line (the category when no detail was identified)."""
        return self.detail.label if self.detail is not None else self.mechanism


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
    stable
        Per speed: the verdict is stable *and decided* (an undecided speed is not stable:
        see ``state``).
    marginal, converged
        Per speed (see :class:`~rheolin.FloquetResult`).
    frequency
        ``|Im|`` of the leading exponent per speed [rad/s] (folded into ``(-w1/2, w1/2]``
        by the dense method, the modal frequency with the lattice method).
    ranges
        The unstable speed ranges.
    decided
        Per speed: the truncation cannot change the verdict (:attr:`FloquetResult.decided`).
    method
        Per speed: the Floquet method used (``"dense"``, ``"sparse"``, ``"lattice"``).
    info
        Totals: Floquet evaluations, seconds, the largest lattice; ``"failed"``: the speeds
        whose check failed numerically (undecided) and why.
    state
        Per speed: ``"stable"``, ``"unstable"`` or ``"undecided"`` (the verdict is not
        decided: the truncation could still flip it, whichever side it leans to).
    max_real_uncertainty
        Per speed: the stated uncertainty of ``max_real`` [1/s]
        (:attr:`FloquetResult.max_real_uncertainty`).
    """

    speeds: np.ndarray
    max_real: np.ndarray
    tol: np.ndarray
    stable: np.ndarray
    marginal: np.ndarray
    converged: np.ndarray
    frequency: np.ndarray
    ranges: list[UnstableRange] = field(default_factory=list)
    decided: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    method: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=str))
    info: dict[str, Any] = field(default_factory=dict)
    state: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=str))
    max_real_uncertainty: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def all_stable(self) -> bool:
        """True when every speed of the sweep is decided stable."""
        return bool(np.all(self.stable))

    @property
    def undecided(self) -> np.ndarray:
        """Per speed: the verdict is undecided."""
        n = self.speeds.size
        if self.state.size == n:
            return np.asarray(self.state == "undecided")
        decided = self.decided if self.decided.size == n else np.ones(n, dtype=bool)
        return ~np.asarray(decided, bool)

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
        n = self.speeds.size
        decided = self.decided if self.decided.size == n else np.ones(n, dtype=bool)
        method = self.method if self.method.size == n else np.full(n, "")
        state = self.state if self.state.size == n else states(self.stable, decided)
        unc = self.max_real_uncertainty
        unc = unc if unc.size == n else np.full(n, np.nan)
        ds = xr.Dataset(
            {
                "decided": (("speed",), decided.astype(bool)),
                "state": (("speed",), state.astype(str)),
                "max_real_uncertainty": (("speed",), unc.astype(float)),
                "floquet_method": (("speed",), method.astype(str)),
                "range_label": (("range",), np.array([r.label for r in rg], str)),
                "max_real": (("speed",), self.max_real),
                "tol": (("speed",), self.tol),
                "stable": (("speed",), self.stable.astype(bool)),
                "marginal": (("speed",), self.marginal.astype(bool)),
                "converged": (("speed",), self.converged.astype(bool)),
                "frequency": (("speed",), self.frequency / (2 * np.pi), {"units": "Hz"}),
                "range_lower": (("range",), np.array([r.lower for r in rg], float)),
                "range_upper": (("range",), np.array([r.upper for r in rg], float)),
                "range_lower_uncertainty": (
                    ("range",),
                    np.array([r.lower_uncertainty for r in rg], float),
                ),
                "range_upper_uncertainty": (
                    ("range",),
                    np.array([r.upper_uncertainty for r in rg], float),
                ),
                "range_lower_open": (("range",), np.array([r.lower_open for r in rg], bool)),
                "range_upper_open": (("range",), np.array([r.upper_open for r in rg], bool)),
                "range_max_real": (("range",), np.array([r.max_real for r in rg], float)),
                "range_mechanism": (("range",), np.array([r.mechanism for r in rg], str)),
            },
            coords={"speed": self.speeds},
        )
        ds["speed"].attrs["units"] = "rad/s"
        ds["max_real"].attrs.update(units="1/s", long_name="largest Floquet real part")
        ds["max_real_uncertainty"].attrs.update(units="1/s")
        for name in ("range_lower", "range_upper", "range_lower_uncertainty"):
            ds[name].attrs["units"] = "rad/s"
        ds["range_upper_uncertainty"].attrs["units"] = "rad/s"
        ds.attrs["title"] = "Floquet stability map"
        return ds


def stability_map(
    model: Any,
    speeds_rad_s: Any,
    *,
    harmonics: Any = None,
    method: str = "auto",
    order: int | None = None,
    refine: float = 1e-8,
    identify_mechanism: bool = True,
    progress: Callable[[int, FloquetResult], None] | None = None,
    memory_budget: Any = None,
    identify: bool | None = None,
    rtol: float | None = None,
    workers: int | None = 1,
    client: Any = None,
    reduce: Any = None,
) -> StabilityMap:
    """Largest Floquet real part of a :class:`~rheolin.mechanics.Model` against speed.

    At every speed the full periodic system is assembled and :func:`rheolin.floquet` decides
    stability with its automatic truncation (dense Hill for small systems, the harmonic
    lattice for gearboxes; balanced pencil, per-exponent tolerances), each speed continued
    from the previous one (:class:`~rheolin.floquet.Continuation`) when it is at most
    :data:`~rheolin.stability.verdicts.CONTINUED_STEP` above it, else from scratch
    (``info["continued"]`` counts the continued speeds). A speed of 0 is the standstill:
    the time-invariant system frozen at ``t = 0`` (:mod:`rheolin.stability.standstill`;
    ``info["standstill"]`` says so). Contiguous samples that
    are not decided stable, with at least one decided unstable, form an
    :class:`UnstableRange`; its bounds are refined between the bracketing decided samples
    to a relative precision ``refine`` where every evaluation is a full, decided verdict
    (:func:`rheolin.stability.ranges.refine_edge`), each with its uncertainty, and its
    mechanism is identified at its worst sample (:mod:`rheolin.stability.mechanism`).

    Parameters
    ----------
    model
        The model.
    speeds_rad_s
        Increasing input speeds [rad/s], >= 0 (0: the standstill).
    harmonics
        Hill truncation: None (automatic), a harmonic set / int (a dense grid), or
        ``callable(system) -> harmonic set``.
    method
        Floquet method: ``"auto"``, ``"dense"``, ``"sparse"`` or ``"lattice"``.
    order
        Lattice order (default: automatic, see :func:`rheolin.floquet`).
    refine
        Relative precision of the range bounds (0: the bounds are the first/last unstable
        samples).
    identify_mechanism
        Identify the mechanism of each range.
    progress
        Called as ``progress(i, result)`` after each speed.
    memory_budget
        Passed to :func:`rheolin.floquet`.
    rtol
        Relative accuracy of each speed's largest real part (:func:`rheolin.floquet`; None:
        not refined beyond what the verdict needs, ``max_real_uncertainty`` says how far).
    workers
        Worker processes for the speeds' verdicts (one BLAS thread each: forked copies of
        this process where that is safe, else a local Dask cluster;
        :func:`~rheolin.study.executor.local_workers`): the speeds are split into contiguous blocks
        (:func:`~rheolin.stability.verdicts.blocks_of`: the runs that are continued from
        speed to speed apart, the longest halved until there are two blocks per worker),
        each continued within itself, and each worker gets its share of the memory budget;
        ``progress`` is then called as each speed's verdict ends on its worker (or, where
        that report is late, as its block ends). 1 (default): in this process. The
        range bounds are refined here afterwards.
    client
        A ``distributed.Client``, or an executor of :mod:`rheolin.study.executor`
        (:func:`~rheolin.study.executor.local_workers`), to run the blocks on instead
        (``workers`` is then ignored).
    reduce
        A large model's map on its Craig-Bampton reduction (:mod:`rheolin.system.reduction`,
        :func:`rheolin.floquet.reduced.floquet_reduced`): the cut-off [rad/s] of the
        fixed-interface modes kept, or True for the default; the basis is made at the first
        speed and shared by the others, and each verdict's uncertainty carries the estimate
        of what the left-out modes change (docs/stability.md, section 9). None: the full
        system at every speed.

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
    >>> round(r.lower, 3), round(r.upper, 3), r.mechanism, r.detail.resonance
    (100.0, 110.0, 'asymmetric shaft band', 'principal')
    """
    import time

    if identify is not None:  # the former keyword
        identify_mechanism = bool(identify)
    speeds = np.asarray(speeds_rad_s, dtype=float).ravel()
    if speeds.size < 1 or np.any(speeds < 0) or np.any(np.diff(speeds) <= 0):
        raise ValueError("`speeds_rad_s` must be >= 0 and strictly increasing [rad/s]")
    if workers is not None and int(workers) < 1:
        raise ValueError(f"`workers` must be >= 1, got {workers}")
    t0 = time.perf_counter()
    task = Verdicts(model, speeds, harmonics, method, order, memory_budget, rtol, reduce=reduce)
    evaluate = task.evaluator()
    parallel = client is not None or (workers is not None and int(workers) > 1)
    if parallel and speeds.size > 1 and not callable(harmonics):
        results, continued = in_parallel(task, workers, client, progress)
    else:
        results, continued = continued_verdicts(task, evaluate, progress)
    smap = map_from_results(
        model,
        speeds,
        results,
        order=order,
        refine=refine,
        identify_mechanism=identify_mechanism,
        memory_budget=memory_budget,
        evaluate=evaluate,
    )
    smap.info["evaluations"] = smap.info.get("evaluations", 0) + speeds.size
    smap.info["continued"] = continued
    if speeds[0] == 0:
        smap.info["standstill"] = STANDSTILL_NOTE
    smap.info["seconds"] = time.perf_counter() - t0
    return smap


def map_from_results(
    model: Any,
    speeds_rad_s: Any,
    results: list[FloquetResult],
    *,
    order: int | None = None,
    refine: float = 1e-8,
    identify_mechanism: bool = True,
    memory_budget: Any = None,
    evaluate: Callable[..., tuple[Any, FloquetResult]] | None = None,
) -> StabilityMap:
    """The stability map from Floquet results already computed at every speed.

    Used by :func:`stability_map`, and by sweeps whose workers check each speed's stability
    as part of the steady-state solve (``Solution.floquet``): only the refinement of the
    range bounds and the naming of the mechanisms are done here. ``evaluate(speed,
    continuation, accuracy[, lattice_order])`` returns ``(assembled, FloquetResult)`` at a
    speed (default: the model's automatic Floquet verdict; with ``lattice_order``, the lattice
    method at that order, not raised); the edges call it with ``accuracy = inf`` (their
    verdicts need to be decided, not refined).
    """
    speeds = np.asarray(speeds_rad_s, dtype=float).ravel()
    if len(results) != speeds.size:
        raise ValueError(f"need one Floquet result per speed, got {len(results)} for {speeds.size}")
    count = [0]

    def default_evaluate(
        W: float,
        continuation: Any = None,
        accuracy: float | None = None,
        lattice_order: int | None = None,
    ) -> tuple[Any, FloquetResult]:
        a = model.assemble(float(W))
        res = floquet(
            a.system,
            method="auto" if lattice_order is None else "lattice",
            order=order if lattice_order is None else lattice_order,
            memory_budget=memory_budget,
            continuation=continuation,
            rtol=accuracy,
        )
        return a, res

    run = evaluate if evaluate is not None else default_evaluate
    decided = np.array([r.decided for r in results], dtype=bool)
    verdicts = np.array([r.stable for r in results], dtype=bool)
    state = states(verdicts, decided)
    smap = StabilityMap(
        speeds=speeds,
        max_real=np.array([r.max_real for r in results]),
        tol=np.array([r.tolerances[0] if r.tolerances.size else r.tol for r in results]),
        stable=state == "stable",
        marginal=np.array([r.marginal for r in results]),
        converged=np.array([r.converged for r in results]),
        frequency=np.array([abs(r.leading.imag) for r in results]),
        decided=decided,
        method=np.array([r.method for r in results]),
        state=state,
        max_real_uncertainty=np.array([_uncertainty(r) for r in results]),
    )
    for i, j in unstable_runs(state):
        worst = i + int(np.argmax(smap.max_real[i : j + 1]))
        lead = results[worst]
        unstable = np.flatnonzero(state[i : j + 1] == "unstable") + i
        lo, hi = float(speeds[i]), float(speeds[j])
        lo_unc = hi_unc = float("nan")
        if i > 0:  # bracket: the decided stable sample below, the first decided unstable one
            k = int(unstable[0])
            edge = edge_between(
                run, count, (speeds[i - 1], results[i - 1]), (speeds[k], results[k]), refine
            )
            lo, lo_unc = edge.speed, edge.uncertainty
        if j < speeds.size - 1:  # and above: the decided stable one, the last unstable one
            k = int(unstable[-1])
            edge = edge_between(
                run, count, (speeds[j + 1], results[j + 1]), (speeds[k], results[k]), refine
            )
            hi, hi_unc = edge.speed, edge.uncertainty
        detail = None
        category = UNIDENTIFIED
        if identify_mechanism and speeds[worst] > 0:  # a standstill has no harmonics
            a, res = (None, lead) if lead.method == "lattice" else (None, None)
            if res is None:  # the dense method has no partner harmonics
                a, res = evaluate_lattice(model, speeds[worst], order, memory_budget)
                count[0] += 1
            if a is None:
                a = model.assemble(float(speeds[worst]))
            detail = _identify(model, a, res)
            category = detail.category or UNIDENTIFIED
        smap.ranges.append(
            UnstableRange(
                float(lo),
                float(hi),
                i == 0,
                j == speeds.size - 1,
                float(smap.max_real[i : j + 1].max()),
                category,
                detail,
                lo_unc,
                hi_unc,
            )
        )
    smap.info = {
        "evaluations": count[0],
        "largest_lattice": max(
            (len(r.lattice) for r in results if r.lattice is not None), default=0
        ),
    }
    failed = {
        float(W): r.info["error"]
        for W, r in zip(speeds, results, strict=True)
        if r.method == "failed"
    }
    if failed:  # speeds whose check failed numerically: undecided, and why
        smap.info["failed"] = failed
    return smap


def evaluate_lattice(model: Any, W: float, order: int | None, budget: Any) -> tuple[Any, Any]:
    """The model at ``W`` and its lattice Floquet result (for naming a mechanism)."""
    a = model.assemble(float(W))
    return a, floquet(a.system, method="lattice", order=order, memory_budget=budget)


def _uncertainty(res: FloquetResult) -> float:
    u = getattr(res, "max_real_uncertainty", float("nan"))
    return float(u) if u is not None else float("nan")


def mechanism(model: Any, assembled: Any, harmonics: Any = None, *, method: str = "auto") -> str:
    """The category of the instability of an assembled model (see
    :mod:`rheolin.stability.mechanism`); ``""`` when it is stable."""
    del harmonics, method  # the lattice method decides and names
    res = floquet(assembled.system, method="lattice")
    return _identify(model, assembled, res).category
