"""The result of a Floquet computation and its verdict (``decided``)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..budget import MemoryBudgetError
from ..errors import ModelError
from ..harmonics.lattice import Lattice

__all__ = [
    "DECIDE_SAFETY",
    "EDGE_TOL",
    "NUMERICAL_FAILURES",
    "REL_FLOOR",
    "SAFETY",
    "SPLIT_FACTOR",
    "TRUNCATION_SAFETY",
    "FloquetResult",
    "add_note",
    "failed_result",
    "guarded",
]

#: What a numerical failure of a stability check raises (a factorization, an eigensolver that
#: did not converge): the verdict is left open, the steady state stands.
NUMERICAL_FAILURES: tuple[type[Exception], ...] = (
    ArithmeticError,
    ValueError,
    RuntimeError,
    np.linalg.LinAlgError,
)


#: An exponent is called unstable only when its real part exceeds this many error bounds.
SAFETY = 100.0


#: Relative floor of the per-exponent tolerance (times ``max(|lambda|, w1)``).
REL_FLOOR = 1e-10


#: Energy fraction allowed at the outermost harmonics for a converged representative.
EDGE_TOL = 1e-6


#: Safety factor on the truncation-error estimate ``sqrt(edge_weight) max(|lambda|, w1)``.
DECIDE_SAFETY = 10.0


#: ... widened by this factor for exponents that may be one of a pair about to split.
SPLIT_FACTOR = 4.0


#: Lattice path: an exponent is decided when ``|Re|`` exceeds this many truncation estimates.
TRUNCATION_SAFETY = 10.0


EPS = float(np.finfo(float).eps)


@dataclass
class FloquetResult:
    """Floquet exponents of the homogeneous system ``M q'' + D q' + K q = 0``.

    Attributes
    ----------
    exponents
        One representative per exponent (``2 n`` of them for a nonsingular ``M_0`` with the
        dense method; those found near the imaginary axis with the sparse one), imaginary
        part in ``(-omega/2, omega/2]``, sorted by decreasing real part.
    max_real
        Largest real part [1/s].
    stable
        True when no exponent has a real part above its own tolerance.
    marginal
        True when stable and some exponent has a real part of zero within its tolerance
        (undamped or rigid-body motion, bounded or linearly growing).
    tol
        Largest per-exponent tolerance (``tolerances.max()``) [1/s].
    omega
        Base angular frequency of the system.
    tolerances
        Per-exponent tolerance: ``SAFETY`` times the first-order error bound
        ``eps (||A|| + |lambda| ||B||) / |y^H B x|`` (left/right eigenvectors ``y``, ``x`` of
        the balanced pencil), at least ``REL_FLOOR * max(|lambda|, omega)``. Multiple or
        ill-conditioned exponents (rigid-body modes, band edges) get wide tolerances.
    edge_weight
        Energy fraction of each representative's eigenvector in the outermost harmonics of
        the truncation; small means converged in the truncation.
    converged
        True when every representative has ``edge_weight <= EDGE_TOL``.
    decided
        True when the truncation cannot change the verdict: every representative that is not
        converged lies far enough from the imaginary axis, ``|Re| > DECIDE_SAFETY
        sqrt(edge_weight) max(|lambda|, omega)`` (an estimate of its truncation error with a
        safety factor of 10), on the side of the verdict; four times that estimate for an
        exponent within it of ``Im = 0`` or ``w1 / 2``, where a complex pair can split into
        a growing real pair (checked on a scan of the damped Mathieu equation). Heavily
        damped high modes that need more harmonics do not make a stability verdict uncertain.
    method
        ``"dense"``, ``"sparse"`` or ``"lattice"``; ``"failed"`` for a check that failed
        numerically (:func:`failed_result`: undecided, the reason in ``info["error"]``).
    band
        Sparse method: every exponent with ``|Re| <= band`` in the searched frequency range
        was found (``inf`` for dense).
    info
        Method details (shifts, factorizations, timings, lattice size and memory estimate).
    truncation
        Lattice method: per-exponent estimate of the truncation error [1/s], the
        second-order correction from the harmonics just outside the lattice. An exponent's
        verdict is decided when ``|Re| > TRUNCATION_SAFETY x truncation``. Empty otherwise.
    complete
        Lattice method: as many exponents were found as the time-averaged system has.
    lattice
        Lattice method: the :class:`~rheolin.harmonics.lattice.Lattice` of the truncation.
    dominant
        Lattice method: for each exponent, the index of the time-averaged mode (in
        ``averaged``) that carries most of its eigenvector at harmonic 0.
    partner
        Lattice method: for each exponent, what it resonates with: ``(shift, mode_a,
        mode_b)``, the time-averaged modes (indices into ``averaged``) dominating its
        eigenvector at two harmonics ``shift`` apart (a mode and its own conjugate for a
        parametric resonance, ``2 w_a ~ |shift| w1``).
    averaged
        Lattice method: the exponents of the time-averaged system.
    averaged_tol
        Lattice method: their tolerances (as ``tolerances``).
    max_real_uncertainty
        Stated uncertainty of ``max_real`` [1/s]. Lattice method: ``TRUNCATION_SAFETY``
        times the leading exponent's truncation estimate (its Gershgorin radius when its
        disc judges it), at least its tolerance; ``rtol`` of :func:`rheolin.floquet` refines
        the lattice near it until this meets ``rtol |max_real|``. Dense and sparse methods:
        its tolerance, or ``DECIDE_SAFETY sqrt(edge_weight) max(|lambda|, omega)`` when its
        eigenvector has not converged in the truncation.

    Notes
    -----
    The dense and sparse methods fold every exponent into ``(-omega/2, omega/2]``. The
    lattice method keeps the copy centred on harmonic 0, whose imaginary part is the modal
    frequency: ``omega`` is input speed / 4757 for a hunting-tooth gearbox, and folding into
    a band of 0.07 rad/s would say nothing.
    """

    exponents: np.ndarray
    max_real: float
    stable: bool
    marginal: bool
    tol: float
    omega: float
    tolerances: np.ndarray = field(default_factory=lambda: np.zeros(0))
    edge_weight: np.ndarray = field(default_factory=lambda: np.zeros(0))
    converged: bool = True
    method: str = "dense"
    band: float = float("inf")
    info: dict[str, Any] = field(default_factory=dict)
    truncation: np.ndarray = field(default_factory=lambda: np.zeros(0))
    complete: bool = True
    lattice: Lattice | None = None
    dominant: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    partner: list[tuple[int, int, int]] = field(default_factory=list)
    averaged: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=complex))
    averaged_tol: np.ndarray = field(default_factory=lambda: np.zeros(0))
    max_real_uncertainty: float = float("nan")

    @property
    def decided(self) -> bool:
        """See the class docstring."""
        if self.method == "failed":
            return False
        if self.method == "lattice":
            return self._decided_lattice()
        if self.converged or self.exponents.size == 0:
            return True
        lam = self.exponents
        loose, reach, clear = self._truncation_reach()
        if not self.stable:
            # unstable for sure when a converged (or clearly growing) exponent says so
            sure = (lam.real > self.tolerances) & (~loose | (lam.real > reach))
            return bool(sure.any())
        return bool(np.all(~loose | clear))

    def _truncation_reach(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Dense and sparse methods: per exponent whether it has not converged in the
        truncation (``loose``), its error estimate ``reach`` and whether that lies left of the
        axis (``clear``; four times over near ``Im = 0`` or ``w1 / 2``, where a pair may
        split into a growing real pair)."""
        lam = self.exponents
        weight = self.edge_weight if self.edge_weight.size == lam.size else np.ones(lam.size)
        loose = weight > EDGE_TOL
        reach = DECIDE_SAFETY * np.sqrt(weight) * np.maximum(np.abs(lam), self.omega)
        half = 0.5 * self.omega
        edge_gap = np.abs(lam.imag / half - np.round(lam.imag / half)) * half
        near_split = edge_gap < reach
        clear = np.where(near_split, lam.real + SPLIT_FACTOR * reach < 0, lam.real + reach < 0)
        return loose, reach, clear

    def _decided_lattice(self) -> bool:
        return self._lattice_verdict()[0]

    def truncation_open(self) -> np.ndarray:
        """Lattice method: the exponents (this result's order) whose truncation estimate
        alone keeps the verdict open, so that a finer lattice near them may decide it;
        none when the verdict is decided or open for another reason (an exponent missing
        or unresolved, Liouville's identity, a band's bound)."""
        if self.method != "lattice":
            return np.zeros(self.exponents.size, dtype=bool)
        return self._lattice_verdict()[1]

    def _lattice_verdict(self) -> tuple[bool, np.ndarray]:
        """Whether the lattice verdict is decided, and the exponents whose truncation keeps
        it open (see :meth:`truncation_open`)."""
        lam, tol = self.exponents, self.tolerances
        none = np.zeros(lam.size, dtype=bool)
        if not self.complete:
            return False, none
        reach = TRUNCATION_SAFETY * self.truncation
        # Liouville: the real parts of all 2 n exponents sum to -mean tr(M^-1 D); a truncation
        # that moved exponents more than their estimates say shows here
        target, unc = self.info.get("liouville", (float("nan"), float("inf")))
        if np.isfinite(target):
            spread = self.info.get("uncertainty", reach)
            slack = float(np.sum(spread) + np.sum(tol)) + unc + 1e-10 * float(np.sum(np.abs(lam)))
            total = float(np.sum(lam.real))
            # modes certified by their Gershgorin discs were not computed: each pair counts
            # with its time-averaged real part, within its radius
            skipped = self.info.get("certified_modes", np.zeros(0, complex))
            radii = self.info.get("certified_radii", np.zeros(0))
            pair = np.where(np.abs(skipped.imag) > 0, 2.0, 1.0)
            total += float(np.sum(pair * skipped.real))
            slack += float(np.sum(pair * radii))
            if abs(total - target) > slack:
                return False, none
        unresolved = self.info.get("unresolved", np.zeros(lam.size, bool))
        if not self.stable:
            sure = (lam.real > tol + reach) & ~unresolved
            if np.any(sure):
                return True, none
            return False, (lam.real > tol) & ~unresolved
        # a band of a large model: the modes left out must be bounded (docs/stability.md, 8)
        band = self.info.get("band")
        if band and not band.get("certified", False):
            return False, none
        certified = self.info.get("certified", np.zeros(lam.size, bool))
        if np.any(unresolved & ~certified):
            return False, none
        blocking = self._truncation_blocking()
        return not bool(np.any(blocking)), blocking

    def _truncation_blocking(self) -> np.ndarray:
        """Lattice method, a stable verdict: the exponents whose truncation estimate reaches
        the axis (four times nearer where a pair may split into a real pair), not certified
        by their discs."""
        lam, tol = self.exponents, self.tolerances
        reach = TRUNCATION_SAFETY * self.truncation
        gap = self.info.get("split_gap", np.full(lam.size, np.inf))
        near_split = gap < 2.0 * reach
        loose = self.truncation > tol
        certified = self.info.get("certified", np.zeros(lam.size, bool))
        split_clear = lam.real + SPLIT_FACTOR * (reach + gap) < 0
        clear = np.where(near_split, split_clear, lam.real + reach < 0)
        return np.asarray(loose & ~clear & ~certified)

    def open_reason(self, most: int = 3) -> str:
        """Why the verdict is not decided, naming (up to ``most``) the exponents that keep it
        open, by real part, the uncertainty that reaches the axis and frequency, and what to
        change; ``""`` when it is decided.

        >>> import numpy as np
        >>> r = floquet_result(np.array([-0.5 + 100j]), np.array([1e-12]), np.array([0.5]),
        ...                    10.0, "dense")
        >>> r.decided, r.open_reason().split(": ")[1].split(". ")[0]
        (False, '-0.5 +- 707 1/s at 15.92 Hz')
        """
        if self.decided:
            return ""
        if self.method == "failed":
            return str(self.info.get("error", "the check failed"))
        lam = self.exponents
        advice = (
            "To decide: more harmonics (a finer lattice; the memory budget "
            "RHEOLIN_MEMORY_BUDGET bounds it), damping where it is physical, or a coarser or "
            "condensed model of the bodies those modes live in"
        )
        if self.method != "lattice":
            loose, reach, clear = self._truncation_reach()
            rows = np.flatnonzero(loose & ~clear)
            what = (
                "exponents not converged in the truncation, whose error estimate reaches the axis"
            )
            return f"{self._listed(what, rows, reach, most)}. {advice}"
        if not self.complete:
            return (
                f"the lattice search found {lam.size} exponents where the time-averaged system "
                f"has {int(self.info.get('expected', 0)) or 'more'}. {advice}"
            )
        band = self.info.get("band")
        if band and not band.get("certified", False):
            return str(band.get("reason") or "the modes the band leaves out are not bounded")
        unresolved = self.info.get("unresolved", np.zeros(lam.size, bool))
        certified = self.info.get("certified", np.zeros(lam.size, bool))
        if self.stable:
            rows_open = np.flatnonzero(self._truncation_blocking() & ~unresolved)
        else:  # growing exponents within their truncation uncertainty of the axis
            rows_open = np.flatnonzero((lam.real > self.tolerances) & ~unresolved)
        parts = [
            self._listed(
                "exponents the lattice does not resolve, the Gershgorin discs of their modes "
                "reaching the axis", np.flatnonzero(unresolved & ~certified), None, most,
            ),
            self._listed(
                "exponents whose truncation uncertainty reaches the axis", rows_open,
                TRUNCATION_SAFETY * self.truncation, most,
            ),
        ]  # fmt: skip
        parts = [p for p in parts if p]
        order = self.lattice.order if self.lattice is not None else "?"
        if not parts:
            return (
                f"the exponents' sum is off Liouville's identity by more than their "
                f"uncertainties at lattice order {order}. {advice}"
            )
        return f"at lattice order {order}, " + "; ".join(parts) + f". {advice}"

    def _listed(self, what: str, rows: np.ndarray, spread: Any, most: int) -> str:
        """``what: re +- spread 1/s at f Hz, ...`` for ``rows`` (largest real part first, a
        complex pair or a folded copy named once, at most ``most``); ``""`` for no row."""
        lam = self.exponents
        named: list[int] = []
        seen: set[tuple[float, float]] = set()
        for i in rows[np.argsort(-lam.real[rows], kind="stable")]:
            key = (round(float(lam[i].real), 9), round(float(abs(lam[i].imag)), 6))
            if key not in seen:
                seen.add(key)
                named.append(int(i))
        if not named:
            return ""
        listed = ", ".join(
            f"{lam[i].real:.4g}"
            + ("" if spread is None else f" +- {spread[i]:.3g}")
            + f" 1/s at {abs(lam[i].imag) / (2 * np.pi):.4g} Hz"
            for i in named[:most]
        )
        more = f" and {len(named) - most} more" if len(named) > most else ""
        return f"{what}: {listed}{more}"

    @property
    def leading(self) -> complex:
        """The exponent with the largest real part (``nan`` when none was found)."""
        return complex(self.exponents[0]) if self.exponents.size else complex("nan")


def floquet_result(
    reps: np.ndarray,
    bounds: np.ndarray,
    edges: np.ndarray,
    w: float,
    method: str,
    band: float = float("inf"),
    info: dict[str, Any] | None = None,
) -> FloquetResult:
    tol_i = np.maximum(SAFETY * bounds, REL_FLOOR * np.maximum(np.abs(reps), w))
    order = np.argsort(-reps.real, kind="stable")
    reps, tol_i, edges = reps[order], tol_i[order], edges[order]
    unstable = reps.real > tol_i
    near_zero = np.abs(reps.real) <= tol_i
    max_real = float(reps.real.max()) if reps.size else float("-inf")
    stable = not bool(unstable.any())
    lead_unc = float("nan")
    if reps.size:
        loose = edges[0] > EDGE_TOL
        reach = DECIDE_SAFETY * np.sqrt(edges[0]) * max(abs(reps[0]), w) if loose else 0.0
        lead_unc = max(float(tol_i[0]), float(reach))
    return FloquetResult(
        exponents=reps,
        max_real=max_real,
        stable=stable,
        marginal=bool(stable and near_zero.any()),
        tol=float(tol_i.max()) if tol_i.size else REL_FLOOR * w,
        omega=w,
        tolerances=tol_i,
        edge_weight=edges,
        converged=bool(np.all(edges <= EDGE_TOL)),
        method=method,
        band=band,
        info=info or {},
        max_real_uncertainty=lead_unc,
    )


def failed_result(reason: str) -> FloquetResult:
    """The verdict of a check that failed numerically: no exponent, undecided, and why in
    ``info["error"]``.

    >>> r = failed_result("ArpackNoConvergence: no convergence")
    >>> r.decided, r.stable, r.info["error"]
    (False, False, 'ArpackNoConvergence: no convergence')
    """
    return FloquetResult(
        exponents=np.zeros(0, dtype=complex),
        max_real=float("nan"),
        stable=False,
        marginal=False,
        tol=float("nan"),
        omega=float("nan"),
        converged=False,
        method="failed",
        complete=False,
        info={"error": reason},
    )


def add_note(info: dict[str, Any], why: str) -> None:
    """Append ``why`` to ``info["note"]`` (``"; "`` between notes).

    >>> info = {"note": "order 1 undecided"}
    >>> add_note(info, "order 2 was stopped"); info["note"]
    'order 1 undecided; order 2 was stopped'
    """
    info["note"] = f"{info['note']}; {why}" if info.get("note") else why


def guarded(check: Callable[..., FloquetResult], *args: Any, **kwargs: Any) -> FloquetResult:
    """``check(*args, **kwargs)``, or its :func:`failed_result` when it fails numerically
    (:data:`NUMERICAL_FAILURES`); a refusal (a :class:`~rheolin.errors.ModelError` such as
    a free body, or the memory budget) is the caller's and propagates.

    >>> def arpack():
    ...     raise RuntimeError("ARPACK error -1: No convergence")
    >>> guarded(arpack).info["error"]
    'RuntimeError: ARPACK error -1: No convergence'
    """
    try:
        return check(*args, **kwargs)
    except (ModelError, MemoryBudgetError):
        raise
    except NUMERICAL_FAILURES as exc:
        return failed_result(f"{type(exc).__name__}: {exc}")
