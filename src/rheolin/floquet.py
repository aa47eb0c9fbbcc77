"""Floquet stability of the periodic system by Hill's method (DESIGN.md §6, docs/stability.md).

Three paths over the same (balanced) Hill pencil ``lambda B y = A y``:

* ``"dense"``: every eigenvalue by QZ, with left eigenvectors for a per-exponent error bound;
* ``"sparse"``: only the exponents near the imaginary axis, by shift-invert Arnoldi
  (``scipy.sparse.linalg.eigs`` on ``(A - sigma B)^-1 B``, one sparse LU per shift) along a
  frequency range; the adjoint problem gives the left eigenvectors for the same error bound;
* ``"lattice"``: for systems whose time variation comes from a few generators (gear meshes,
  shafts), the Hill problem on the lattice of their integer combinations, solved near every
  mode of the time-averaged system (:mod:`rheolin.floquet_lattice`).

The dense and sparse paths need a dense grid ``-N..N`` (in units of the gcd of its indices);
any other harmonic set is refused, because their choice of representatives and their
truncation test assume one.

Representatives are the copies whose eigenvector is centred on harmonic 0 (smallest
energy-weighted mean of ``|n|``; the signed mean would also pick spurious eigenvectors split
between the two ends of the truncation), folded into ``(-w1/2, w1/2]``.
"""

from __future__ import annotations

import logging
import warnings
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .budget import MemoryBudgetError, format_bytes
from .budget import memory_budget as resolve_budget
from .harmonics import HarmonicSet, as_harmonic_set
from .hill import _dense, _diag, hill_matrices, hill_pencil
from .lattice import Lattice, system_lattice
from .system import PeriodicSystem

__all__ = [
    "DEFAULT_LATTICE_ORDER",
    "MAX_DENSE_HILL",
    "FloquetResult",
    "dense_stability_harmonics",
    "floquet",
    "floquet_memory",
    "hill_matrices",
    "hill_pencil",
]

log = logging.getLogger(__name__)

#: Dense Hill matrices beyond this size are refused (sparse shift-invert is the way there).
MAX_DENSE_HILL = 6000
#: ``method="auto"`` uses the dense path up to this Hill size, the sparse one beyond.
AUTO_DENSE_LIMIT = 1500
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
#: Dense path: reduce to the standard problem ``B^-1 A`` when ``rcond(B)`` exceeds this.
STANDARD_RCOND = 1e-4
#: Lattice path: an exponent is decided when ``|Re|`` exceeds this many truncation estimates.
TRUNCATION_SAFETY = 10.0
#: Lattice order of ``floquet(system)`` (raised by one where the verdict is undecided).
DEFAULT_LATTICE_ORDER = 2

_EPS = float(np.finfo(float).eps)


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
        ``"dense"`` or ``"sparse"``.
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
        Lattice method: the :class:`~rheolin.lattice.Lattice` of the truncation.
    dominant
        Lattice method: for each exponent, the index of the time-averaged mode (in
        ``averaged``) that carries most of its eigenvector at harmonic 0.
    partner
        Lattice method: for each exponent, the harmonic ``h`` other than 0 that carries most
        of its eigenvector's energy (what it resonates with) and the time-averaged mode that
        dominates the eigenvector there (an index into ``averaged``).
    averaged
        Lattice method: the exponents of the time-averaged system.
    averaged_tol
        Lattice method: their tolerances (as ``tolerances``).

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
    partner: list[tuple[int, int]] = field(default_factory=list)
    averaged: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=complex))
    averaged_tol: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def decided(self) -> bool:
        """See the class docstring."""
        if self.method == "lattice":
            return self._decided_lattice()
        if self.converged or self.exponents.size == 0:
            return True
        lam = self.exponents
        weight = self.edge_weight if self.edge_weight.size == lam.size else np.ones(lam.size)
        loose = weight > EDGE_TOL
        reach = DECIDE_SAFETY * np.sqrt(weight) * np.maximum(np.abs(lam), self.omega)
        # an exponent near Im = 0 or w1/2 may be one of a pair about to split into a real pair
        half = 0.5 * self.omega
        edge_gap = np.abs(lam.imag / half - np.round(lam.imag / half)) * half
        near_split = edge_gap < reach
        if not self.stable:
            # unstable for sure when a converged (or clearly growing) exponent says so
            sure = (lam.real > self.tolerances) & (~loose | (lam.real > reach))
            return bool(sure.any())
        clear = np.where(near_split, lam.real + SPLIT_FACTOR * reach < 0, lam.real + reach < 0)
        return bool(np.all(~loose | clear))

    def _decided_lattice(self) -> bool:
        if not self.complete:
            return False
        lam, tol = self.exponents, self.tolerances
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
                return False
        if not self.stable:
            sure = (lam.real > tol + reach) & ~self.info.get("unresolved", np.zeros(lam.size, bool))
            return bool(np.any(sure))
        gap = self.info.get("split_gap", np.full(lam.size, np.inf))
        near_split = gap < 2.0 * reach
        loose = self.truncation > tol
        unresolved = self.info.get("unresolved", np.zeros(lam.size, bool))
        certified = self.info.get("certified", np.zeros(lam.size, bool))
        if np.any(unresolved & ~certified):
            return False
        split_clear = lam.real + SPLIT_FACTOR * (reach + gap) < 0
        clear = np.where(near_split, split_clear, lam.real + reach < 0)
        return bool(np.all(~loose | clear | certified))

    @property
    def leading(self) -> complex:
        """The exponent with the largest real part (``nan`` when none was found)."""
        return complex(self.exponents[0]) if self.exponents.size else complex("nan")


def floquet(
    system: PeriodicSystem,
    harmonics: HarmonicSet | Lattice | int | Iterable[int] | None = None,
    *,
    method: str = "auto",
    order: int | None = None,
    frequencies: tuple[float, float] | None = None,
    k: int = 24,
    max_shifts: int = 200,
    memory_budget: str | int | float | None = None,
    near: Any = None,
) -> FloquetResult:
    """Floquet exponents by Hill's method.

    The truncated Hill pencil has a copy of every exponent for each harmonic, shifted by
    ``i h w1``; the representative kept is the eigenvalue whose eigenvector is centred on
    harmonic 0. The pencil is balanced first (:func:`~rheolin.hill.state_scaling`) and every
    exponent carries its own tolerance from its condition number, so stiff springs next to
    soft ones, rigid-body modes and undamped modes do not turn into false instabilities.

    Parameters
    ----------
    system
        The periodic system (the load is ignored).
    harmonics
        The truncation. ``None`` (default) chooses: the time-averaged eigenproblem for a
        time-invariant system; the dense grid of :func:`dense_stability_harmonics` when its
        Hill matrix is small; else the lattice of :func:`~rheolin.lattice.system_lattice`.
        An int ``N`` means ``-N..N``; a :class:`~rheolin.lattice.Lattice` selects the lattice
        method. The dense and sparse methods accept only dense grids (multiples of one
        step), because their representatives and truncation test assume one.
    method
        ``"auto"``, ``"dense"`` (all exponents, QZ), ``"sparse"`` (exponents near the
        imaginary axis, shift-invert) or ``"lattice"`` (module :mod:`rheolin.floquet_lattice`).
    order
        Lattice order. ``None``: :data:`DEFAULT_LATTICE_ORDER`, raised by one when the
        verdict is undecided and the larger lattice fits the memory budget.
    frequencies
        Sparse method: range ``(lo, hi)`` [rad/s] of the (unfolded) imaginary parts searched,
        default ``(0, max|H| w1 / 2)``: modes up to half the truncation frequency, which is
        where the centred copies have room for their sidebands. Real systems have conjugate
        exponents, so only ``Im >= 0`` is searched and the conjugates are added.
    k
        Sparse method: eigenvalues per shift.
    max_shifts
        Sparse method: cap on the number of shifts (factorizations).
    near
        Lattice method: search only near the time-averaged modes closest to these values
        (tracking one exponent across speeds). The result is partial (``complete`` is
        False, ``decided`` too).
    memory_budget
        Refuse (:class:`~rheolin.budget.MemoryBudgetError`, before allocating) when the
        estimated memory exceeds it (bytes or ``"4 GB"``; default
        :func:`rheolin.budget.memory_budget`). The automatic choice lowers the lattice order
        instead, and says so in ``info["note"]``.

    Examples
    --------
    Mathieu's equation ``y'' + (a - 2 q cos 2t) y = 0`` at ``a = 1, q = 0.2`` lies inside the
    first instability band ``(b_1, a_1)``:

    >>> import numpy as np, rheolin as rl
    >>> s = rl.PeriodicSystem(2.0, M={0: np.eye(1)}, K={0: np.eye(1), 1: -0.2 * np.eye(1)})
    >>> res = rl.floquet(s, 10)
    >>> res.stable, len(res.exponents), res.converged
    (False, 2, True)
    >>> bool(abs(rl.floquet(s, 10, method="sparse").max_real - res.max_real) < 1e-10)
    True
    >>> lat = rl.floquet(s, method="lattice", order=10)
    >>> lat.method, bool(abs(lat.max_real - res.max_real) < 1e-10), lat.decided
    ('lattice', True, True)
    """
    allowed = ("auto", "dense", "sparse", "lattice")
    if method not in allowed:
        raise ValueError(f"`method` must be one of {list(allowed)}, got {method!r}")
    budget = memory_budget
    if isinstance(harmonics, Lattice):
        if method not in ("auto", "lattice"):
            raise ValueError(
                f"a Lattice truncation needs method='lattice' (or 'auto'), got {method!r}"
            )
        return _floquet_lattice(system, harmonics, budget=budget, near=near)
    if near is not None and method != "lattice":
        raise ValueError("`near` needs method='lattice'")
    if method == "lattice":
        if harmonics is not None:
            raise ValueError(
                "method='lattice' builds its own truncation: pass `order` (and no `harmonics`), "
                "or a rheolin.lattice.Lattice as `harmonics`"
            )
        return _lattice_auto(
            system, order, budget, refine=order is None and near is None, near=near
        )
    if harmonics is None:
        if system.time_invariant:
            hset = HarmonicSet([0])
        else:
            if (
                method == "auto"
                and 2 * system.n * (2 * _dense_order(system) + 1) > AUTO_DENSE_LIMIT
            ):
                return _lattice_auto(system, order, budget, refine=order is None)
            hset = dense_stability_harmonics(system)
    else:
        hset = as_harmonic_set(harmonics)
    _require_grid(hset)
    size = 2 * system.n * len(hset)
    if method == "auto":
        method = "dense" if size <= AUTO_DENSE_LIMIT else "sparse"
    if method == "dense":
        if size > MAX_DENSE_HILL:
            raise ValueError(
                f"the dense Hill matrix would have size {size} (2 x n x |H|) > {MAX_DENSE_HILL}; "
                "reduce `harmonics` or the model size, or use method='sparse'"
            )
        _check_budget(size * size * 16 * 7, budget, "the dense Hill problem", "fewer harmonics")
        with np.errstate(under="ignore"):  # far harmonics of eigenvectors underflow harmlessly
            return _floquet_dense(system, hset)
    if isinstance(k, bool) or int(k) < 1:
        raise ValueError(f"`k` must be a positive integer, got {k!r}")
    with np.errstate(under="ignore"):
        return _floquet_sparse(system, hset, frequencies, int(k), int(max_shifts))


def _dense_order(system: PeriodicSystem) -> int:
    kmax = max((abs(k) for k in system.coefficient_harmonics), default=0)
    return 2 * kmax + 4 if kmax else 0


def dense_stability_harmonics(system: PeriodicSystem) -> HarmonicSet:
    """Dense Hill truncation ``-N..N`` with ``N`` twice the widest coefficient harmonic + 4
    (``{0}`` for a time-invariant system)."""
    return HarmonicSet.full(_dense_order(system))


def _require_grid(hset: HarmonicSet) -> None:
    """Dense and sparse Hill need ``{-N s, ..., N s}``: refuse any other set."""
    H = hset.indices
    step = int(np.gcd.reduce(np.abs(H))) or 1
    N = int(H.max()) // step
    if H.size != 2 * N + 1 or not np.array_equal(H, step * np.arange(-N, N + 1)):
        raise ValueError(
            f"`harmonics` must be a dense grid -N..N (times one step) for the dense and sparse "
            f"Hill methods; this set has {H.size} of the {2 * N + 1} multiples of {step} up to "
            f"{N * step}. Their representatives and truncation test assume a grid and would "
            "judge a lattice wrongly: use method='lattice' (rl.floquet(system, "
            "method='lattice', order=p)) or pass a rheolin.lattice.Lattice"
        )


def _check_budget(estimate: int, budget: Any, what: str, advice: str) -> None:
    limit = resolve_budget(budget)
    if estimate > limit:
        raise MemoryBudgetError(
            f"{what} needs an estimated {format_bytes(estimate)}, more than the memory budget "
            f"of {format_bytes(limit)}; {advice}, or raise the budget (RHEOLIN_MEMORY_BUDGET "
            "or `memory_budget`)"
        )


def floquet_memory(system: PeriodicSystem, order: int | None = None) -> tuple[str, int]:
    """The method ``floquet(system)`` would use and its estimated memory [bytes].

    For the lattice method ``order`` is the lattice order (default
    :data:`DEFAULT_LATTICE_ORDER`). Nothing large is built.
    """
    from .floquet_lattice import lattice_memory

    if system.time_invariant:
        size = 2 * system.n
        if size <= AUTO_DENSE_LIMIT:
            return "dense", size * size * 16 * 7
        return "sparse", int(system.n * 16 * 400 + 200 * 2**20)
    size = 2 * system.n * (2 * _dense_order(system) + 1)
    if size <= AUTO_DENSE_LIMIT:
        return "dense", size * size * 16 * 7
    p = DEFAULT_LATTICE_ORDER if order is None else int(order)
    return "lattice", lattice_memory(system, system_lattice(system, p, max_size=10**6))


def _lattice_auto(
    system: PeriodicSystem, order: int | None, budget: Any, *, refine: bool, near: Any = None
) -> FloquetResult:
    """Lattice method at ``order`` (default order, lowered to fit the budget, raised by one
    when undecided and the larger lattice fits)."""
    from .floquet_lattice import lattice_memory

    limit = resolve_budget(budget)
    p = DEFAULT_LATTICE_ORDER if order is None else int(order)
    note = ""
    lat = system_lattice(system, p, max_size=10**6)
    est = lattice_memory(system, lat)
    while est > limit and order is None and p > 1:
        p -= 1
        lat = system_lattice(system, p, max_size=10**6)
        est = lattice_memory(system, lat)
        note = (
            f"lattice order lowered to {p} to fit the memory budget of {format_bytes(limit)} "
            "(a coarser truncation: the verdict may be undecided)"
        )
    res = _floquet_lattice(system, lat, budget=budget, near=near)
    if note:
        res.info["note"] = note
    if refine and not res.decided:
        finer = system_lattice(system, p + 1, max_size=10**6)
        if lattice_memory(system, finer) <= limit:
            log.info("floquet: order %d undecided; refining to order %d", p, p + 1)
            res2 = _floquet_lattice(system, finer, budget=budget)
            res2.info["refined_from"] = p
            return res2
        more = f"undecided at lattice order {p}; order {p + 1} would exceed the memory budget"
        res.info["note"] = f"{note}; {more}" if note else more
    return res


def _floquet_lattice(
    system: PeriodicSystem, lattice: Lattice, *, budget: Any, near: Any = None
) -> FloquetResult:
    import time

    from .floquet_lattice import confirm_unresolved, lattice_exponents, lattice_memory

    t0 = time.perf_counter()
    est = lattice_memory(system, lattice)
    _check_budget(
        est,
        budget,
        f"the lattice Hill problem (order {lattice.order}, {len(lattice)} harmonics, "
        f"size {2 * system.n * len(lattice)})",
        "lower the lattice order",
    )
    with np.errstate(under="ignore"), _single_thread_blas():
        out = lattice_exponents(system, lattice, near=near)
        # unresolved exponents: search their clusters again on finer lattices (p + 1, p + 2),
        # only near them, as long as the memory budget allows
        finer: Lattice | None = lattice
        steps: list[Any] = []
        while near is None and np.any(out.unresolved & ~out.certified) and len(steps) < 2:
            finer = _finer(system, finer) if finer is not None else None
            if finer is None or lattice_memory(system, finer) > resolve_budget(budget):
                break
            out = confirm_unresolved(system, out, finer)
            steps.append(out.info.pop("confirmed"))
        if steps:
            out.info["confirmed"] = steps
    w = system.omega
    res = _result(out.exponents, out.bounds, out.edge, w, "lattice", info=out.info)
    order = np.argsort(-out.exponents.real, kind="stable")
    res.truncation = out.truncation[order]
    res.info["order"] = out.order[order]
    res.info["uncertainty"] = out.uncertainty[order]
    res.dominant = out.dominant[order]
    res.partner = [out.partner[i] for i in order]
    res.complete = out.complete and near is None
    res.lattice = lattice
    res.averaged = out.averaged
    res.averaged_tol = out.averaged_tol
    res.info["memory_estimate"] = est
    res.info["seconds"] = time.perf_counter() - t0
    res.info["centroid"] = out.centroid[order]
    res.info["split_gap"] = out.split_gap[order]
    res.info["unresolved"] = out.unresolved[order]
    res.info["certified"] = out.certified[order]
    for key in ("certified_modes", "certified_radii"):
        res.info[key] = out.info.get(key)
    if "confirmed" in out.info:
        res.info["confirmed"] = out.info["confirmed"]
    res.info["liouville"] = out.liouville
    return res


def _finer(system: PeriodicSystem, lattice: Lattice) -> Lattice | None:
    """The lattice of the next order with the same steps (None past ``max_size``)."""
    from .lattice import harmonic_lattice

    steps = dict(zip(lattice.generators, lattice.costs, strict=True))
    if not steps:
        return None
    try:
        return harmonic_lattice(steps, lattice.order + 1, max_size=10**6)
    except ValueError:
        return None


class _single_thread_blas:
    """Limit BLAS to one thread: the lattice kernels are many small products, where
    threads cost more than they bring (2x slower on the gearbox with two)."""

    def __enter__(self) -> None:
        try:
            from threadpoolctl import threadpool_limits
        except ImportError:  # pragma: no cover - threadpoolctl is a dependency
            self._ctx = None
            return
        self._ctx = threadpool_limits(limits=1, user_api="blas")
        self._ctx.__enter__()

    def __exit__(self, *exc: Any) -> None:
        if self._ctx is not None:
            self._ctx.__exit__(*exc)


# ----------------------------------------------------------------------------- shared pieces
def _harmonic_energy(vecs: np.ndarray, n_h: int, n: int) -> np.ndarray:
    """Energy fraction per harmonic, shape ``(|H|, n_vec)``."""
    with np.errstate(under="ignore"):
        energy = np.abs(vecs) ** 2
    per_h = energy.reshape(n_h, 2 * n, -1).sum(axis=1)
    total = per_h.sum(axis=0, keepdims=True)
    return per_h / np.where(total > 0, total, 1.0)


def _edge_weight(per_h: np.ndarray, H: np.ndarray, exact: bool = False) -> np.ndarray:
    """Energy fraction in the two outermost harmonics (0 when the truncation is exact)."""
    if exact:
        return np.zeros(per_h.shape[1])
    if H.size < 3:
        return per_h.sum(axis=0) if H.size else np.zeros(per_h.shape[1])
    return np.asarray(per_h[0] + per_h[-1])


def _fold(lam: np.ndarray, w: float) -> np.ndarray:
    shift = np.ceil(lam.imag / w - 0.5)
    return np.asarray(lam - 1j * w * shift)


def _error_bound(
    lam: np.ndarray, x: np.ndarray, y: np.ndarray, B: Any, normA: float, normB: float
) -> np.ndarray:
    """First-order bound ``eps (||A|| + |lam| ||B||) ||x|| ||y|| / |y^H B x|`` per column."""
    with np.errstate(under="ignore"):
        Bx = B @ x
        denom = np.abs(np.einsum("ij,ij->j", y.conj(), Bx))
        nx = np.linalg.norm(x, axis=0)
        ny = np.linalg.norm(y, axis=0)
    tiny = np.finfo(float).tiny
    return np.asarray(_EPS * (normA + np.abs(lam) * normB) * nx * ny / np.maximum(denom, tiny))


def _result(
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
    )


# ----------------------------------------------------------------------------- dense
def _floquet_dense(system: PeriodicSystem, hset: HarmonicSet) -> FloquetResult:
    A_sp, B_sp = hill_pencil(system, hset)
    A, B = A_sp.toarray(), B_sp.toarray()
    lam, vl, vr, factor = _pencil_eig(A, B)
    finite = np.isfinite(lam)
    lam, vl, vr = lam[finite], vl[:, finite], vr[:, finite]
    H = hset.indices
    n, w = system.n, system.omega
    per_h = _harmonic_energy(vr, H.size, n)
    centroid = np.abs(H).astype(float) @ per_h
    expected = min(2 * n - _massless_count(system), lam.size)
    step = int(np.gcd.reduce(np.abs(H))) or 1
    normA, normB = factor * float(np.linalg.norm(A, 1)), factor * float(np.linalg.norm(B, 1))
    bounds = _error_bound(lam, vr, vl, B, normA, normB)
    order = _representatives(lam, vr, centroid, w, limit=expected, step=step, bounds=bounds)
    if order.size < expected:  # ill-separated copies: fall back to the best centred ones
        order = np.argsort(np.abs(centroid), kind="stable")[:expected]
    return _result(
        _fold(lam[order], w),
        bounds[order],
        _edge_weight(per_h[:, order], H, system.time_invariant),
        w,
        "dense",
        info={"size": A.shape[0]},
    )


def _pencil_eig(A: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Eigenvalues, left and right eigenvectors of ``lambda B x = A x`` and an error factor.

    With a well-conditioned ``B`` (every DOF has inertia) the pencil is reduced to the
    standard problem ``B^-1 A`` (about four times faster than QZ); the left vectors of the
    pencil are ``y = B^-H u``. The reduction's backward error is that of QZ times
    ``cond(B)``, returned as the factor for the error bounds (1 for QZ). A singular or
    ill-conditioned ``B`` keeps QZ.
    """
    with warnings.catch_warnings():  # a singular B (massless DOFs) is expected: QZ below
        warnings.simplefilter("ignore", sla.LinAlgWarning)
        lu, piv = sla.lu_factor(B, check_finite=False)
    gecon = sla.get_lapack_funcs("gecon", (lu,))
    rcond, info = gecon(lu, float(np.linalg.norm(B, 1)), norm="1")
    if info == 0 and rcond > STANDARD_RCOND:
        C = sla.lu_solve((lu, piv), A, check_finite=False)
        lam, ul, vr = sla.eig(C, left=True, right=True, check_finite=False)
        vl = sla.lu_solve((lu, piv), ul, trans=2, check_finite=False)
        return lam, vl, vr, 1.0 / float(rcond)
    lam, vl, vr = sla.eig(A, B, left=True, right=True, check_finite=False)
    return lam, vl, vr, 1.0


def _massless_count(system: PeriodicSystem) -> int:
    """Rank deficiency of ``M_0`` (DOFs without inertia have no oscillatory exponents)."""
    M0 = system.M.get(0)
    if M0 is None:
        return system.n
    if system.n > 2000:  # sparse models: count empty diagonal entries (lumped-mass DOFs)
        return int(np.sum(_diag(M0, system.n) == 0))
    s = np.linalg.svd(_dense(M0), compute_uv=False)
    return int(np.sum(s <= 1e-12 * s.max())) if s.size and s.max() > 0 else system.n


# ----------------------------------------------------------------------------- sparse
def _shift_invert(
    A: sp.csc_array, B: sp.csc_array, sigma: complex, k: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``k`` eigenvalues of ``lambda B x = A x`` nearest ``sigma`` with right and left vectors."""
    size = A.shape[0]
    lu = spla.splu(sp.csc_array(A - sigma * B), permc_spec="MMD_ATA")
    op = spla.LinearOperator(
        (size, size), matvec=lambda x: lu.solve(np.asarray(B @ x)), dtype=complex
    )
    opH = spla.LinearOperator(
        (size, size),
        matvec=lambda x: np.asarray(B.conj().T @ lu.solve(np.asarray(x), trans="H")),
        dtype=complex,
    )
    kk = min(k, size - 2)
    nu, x = spla.eigs(op, k=kk, which="LM", tol=1e-13)
    mu, wl = spla.eigs(opH, k=kk, which="LM", tol=1e-13)
    lam = sigma + 1.0 / nu
    # left eigenvectors: y = (A - sigma B)^-H w, matched to the right ones by eigenvalue
    y_all = np.column_stack([lu.solve(wl[:, j], trans="H") for j in range(kk)])
    lam_left = sigma + 1.0 / np.conj(mu)
    match = np.argmin(np.abs(lam[:, None] - lam_left[None, :]), axis=1)
    return lam, x, y_all[:, match]


def _floquet_sparse(
    system: PeriodicSystem,
    hset: HarmonicSet,
    frequencies: tuple[float, float] | None,
    k: int,
    max_shifts: int,
) -> FloquetResult:
    import time

    t0 = time.perf_counter()
    A, B = hill_pencil(system, hset)
    H = hset.indices
    n, w = system.n, system.omega
    lo, hi = frequencies if frequencies is not None else (0.0, max(abs(H).max() * w / 2, w))
    if not 0.0 <= lo < hi:
        raise ValueError(f"`frequencies` must be (lo, hi) with 0 <= lo < hi, got {frequencies!r}")
    normA, normB = spla.norm(A, 1), spla.norm(B, 1)
    lams: list[np.ndarray] = []
    xs: list[np.ndarray] = []
    ys: list[np.ndarray] = []
    disks: list[tuple[complex, float]] = []
    omega = lo
    alpha = 1e-4 * w
    while omega <= hi and len(disks) < max_shifts:
        sigma = alpha + 1j * omega
        try:
            lam, x, y = _shift_invert(A, B, sigma, k)
        except RuntimeError:  # exactly singular: move the shift slightly
            sigma += 1e-3 * w * (1 + 1j)
            lam, x, y = _shift_invert(A, B, sigma, k)
        radius = float(np.abs(lam - sigma).max())
        disks.append((sigma, radius))
        lams.append(lam)
        xs.append(x)
        ys.append(y)
        omega = sigma.imag + max(radius, (hi - lo) / max_shifts)
    lam = np.concatenate(lams)
    x, y = np.hstack(xs), np.hstack(ys)
    per_h = _harmonic_energy(x, H.size, n)
    centroid = np.abs(H).astype(float) @ per_h
    source = np.concatenate([np.full(v.size, i) for i, v in enumerate(lams)])
    step = int(np.gcd.reduce(np.abs(H))) or 1
    all_bounds = _error_bound(lam, x, y, B, normA, normB)
    keep = _representatives(lam, x, centroid, w, source=source, step=step, bounds=all_bounds)
    bounds = all_bounds[keep]
    reps, edges = _fold(lam[keep], w), _edge_weight(per_h[:, keep], H, system.time_invariant)
    # conjugate exponents of a real system (Im < 0 copies were not searched)
    conj = np.abs(reps.imag) > 1e-9 * np.maximum(np.abs(reps), w)
    conj &= np.abs(np.abs(reps.imag) - w / 2) > 1e-9 * w
    reps = np.concatenate([reps, _fold(reps[conj].conj(), w)])
    bounds = np.concatenate([bounds, bounds[conj]])
    edges = np.concatenate([edges, edges[conj]])
    band = _coverage(disks, lo, hi)
    info = {
        "shifts": [complex(s) for s, _ in disks],
        "radii": [r for _, r in disks],
        "factorizations": len(disks),
        "size": A.shape[0],
        "frequencies": (lo, hi),
        "seconds": time.perf_counter() - t0,
    }
    if omega <= hi:
        log.warning("floquet(sparse): stopped at %d shifts below %.6g rad/s", max_shifts, hi)
        info["incomplete"] = True
    return _result(reps, bounds, edges, w, "sparse", band=band, info=info)


def _representatives(
    lam: np.ndarray,
    x: np.ndarray,
    centroid: np.ndarray,
    w: float,
    limit: int | None = None,
    source: np.ndarray | None = None,
    step: int = 1,
    bounds: np.ndarray | None = None,
) -> np.ndarray:
    """Indices of distinct exponents, best centred first.

    Two eigenvalues whose difference is ``i j w1`` with ``j != 0`` a multiple of ``step`` (the
    gcd of the harmonic set) are copies of one exponent
    (the better centred one is kept); equal eigenvalues with non-parallel eigenvectors are a
    multiple exponent (both kept); the same eigenpair found twice (from two ``source``
    shifts, parallel eigenvectors) counts once.
    """
    order = np.argsort(np.abs(centroid), kind="stable")
    kept: list[int] = []
    for i in order:
        if limit is not None and len(kept) >= limit:
            break
        dup = False
        for j in kept:
            diff = lam[i] - lam[j]
            shift = round(diff.imag / w)
            close = 1e-9 * max(abs(lam[i]), w) + 1e-6 * w
            if bounds is not None:  # ill-conditioned exponents (Jordan blocks) scatter more
                close += SAFETY * (bounds[i] + bounds[j])
            if shift % step or abs(diff - 1j * shift * w) > close:
                continue
            if shift != 0:
                dup = True  # another copy of an exponent already kept
                break
            if source is None or source[i] == source[j]:
                continue
            xi, xj = x[:, i], x[:, j]
            with np.errstate(under="ignore"):
                cos = abs(np.vdot(xi, xj)) / (np.linalg.norm(xi) * np.linalg.norm(xj))
            if cos > 0.99:
                dup = True
                break
        if not dup:
            kept.append(int(i))
    return np.array(kept, dtype=int)


def _coverage(disks: list[tuple[complex, float]], lo: float, hi: float) -> float:
    """Smallest half-width ``|Re|`` covered by the union of the disks along ``[lo, hi]``."""
    grid = np.linspace(lo, hi, 2001)
    half = np.zeros_like(grid)
    for s, r in disks:
        d2 = r * r - (grid - s.imag) ** 2
        h = np.sqrt(np.maximum(d2, 0.0)) - abs(s.real)
        half = np.maximum(half, np.where(d2 > 0, h, 0.0))
    return float(max(half.min(), 0.0))
