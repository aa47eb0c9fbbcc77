"""Floquet stability of the periodic system by Hill's method (DESIGN.md §6).

Two paths over the same (balanced) Hill pencil ``lambda B y = A y``:

* ``"dense"``: every eigenvalue by QZ, with left eigenvectors for a per-exponent error bound;
* ``"sparse"``: only the exponents near the imaginary axis, by shift-invert Arnoldi
  (``scipy.sparse.linalg.eigs`` on ``(A - sigma B)^-1 B``, one sparse LU per shift) along a
  frequency range; the adjoint problem gives the left eigenvectors for the same error bound.

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

from .harmonics import HarmonicSet, as_harmonic_set
from .hill import _dense, _diag, hill_matrices, hill_pencil
from .system import PeriodicSystem

__all__ = ["MAX_DENSE_HILL", "FloquetResult", "floquet", "hill_matrices", "hill_pencil"]

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
        Method details (shifts, factorizations, timings).
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

    @property
    def decided(self) -> bool:
        """See the class docstring."""
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

    @property
    def dominant(self) -> complex:
        """The exponent with the largest real part (``nan`` when none was found)."""
        return complex(self.exponents[0]) if self.exponents.size else complex("nan")


def floquet(
    system: PeriodicSystem,
    harmonics: HarmonicSet | int | Iterable[int],
    *,
    method: str = "auto",
    frequencies: tuple[float, float] | None = None,
    k: int = 24,
    max_shifts: int = 200,
) -> FloquetResult:
    """Floquet exponents by Hill's method.

    The truncated Hill pencil has ``|H|`` copies of every exponent, shifted by ``i k w1``;
    the representative kept is the eigenvalue whose eigenvector is centred on harmonic 0
    (smallest energy-weighted mean of ``|n|``), folded into ``(-w1/2, w1/2]``. The pencil
    is balanced first (:func:`~rheolin.hill.state_scaling`) and every exponent carries its
    own tolerance from its condition number, so stiff springs next to soft ones, rigid-body
    modes and undamped modes do not turn into false instabilities.

    Parameters
    ----------
    system
        The periodic system (the load is ignored).
    harmonics
        Harmonic set for the Hill truncation: an int ``N`` means ``-N..N``. Use a dense
        set: Floquet modes are not restricted to the load's harmonics.
    method
        ``"dense"`` (all exponents, QZ), ``"sparse"`` (exponents near the imaginary axis,
        shift-invert) or ``"auto"`` (dense up to a Hill size of ``AUTO_DENSE_LIMIT``).
    frequencies
        Sparse method: range ``(lo, hi)`` [rad/s] of the (unfolded) imaginary parts searched,
        default ``(0, max|H| w1 / 2)``: modes up to half the truncation frequency, which is
        where the centred copies have room for their sidebands. Real systems have conjugate
        exponents, so only ``Im >= 0`` is searched and the conjugates are added.
    k
        Sparse method: eigenvalues per shift.
    max_shifts
        Sparse method: cap on the number of shifts (factorizations).

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
    """
    hset = as_harmonic_set(harmonics)
    size = 2 * system.n * len(hset)
    allowed = ("auto", "dense", "sparse")
    if method not in allowed:
        raise ValueError(f"`method` must be one of {list(allowed)}, got {method!r}")
    if method == "auto":
        method = "dense" if size <= AUTO_DENSE_LIMIT else "sparse"
    if method == "dense":
        if size > MAX_DENSE_HILL:
            raise ValueError(
                f"the dense Hill matrix would have size {size} (2 x n x |H|) > {MAX_DENSE_HILL}; "
                "reduce `harmonics` or the model size, or use method='sparse'"
            )
        with np.errstate(under="ignore"):  # far harmonics of eigenvectors underflow harmlessly
            return _floquet_dense(system, hset)
    if isinstance(k, bool) or int(k) < 1:
        raise ValueError(f"`k` must be a positive integer, got {k!r}")
    with np.errstate(under="ignore"):
        return _floquet_sparse(system, hset, frequencies, int(k), int(max_shifts))


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
