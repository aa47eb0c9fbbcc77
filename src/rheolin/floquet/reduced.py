"""The lattice verdict of a large system on its Craig-Bampton reduction, with an estimate of
what the left-out modes change (docs/stability.md, section 9).

On a lattice ``H`` the reduced Hill operator is the Galerkin projection of the full one,
``Q_r(lambda) = T^T Q(lambda) T`` (``T`` per harmonic, :mod:`rheolin.system.reduction`).
A reduced exponent ``lambda`` with right and left vectors ``p``, ``z`` lifts to ``y = T p``,
``u = T z``, whose residuals ``r = Q(lambda) y`` and ``l = Q(lambda)^H u`` vanish on the
boundary's and the kept modes' rows (``T^T r = 0``). The full exponent is ``lambda + delta``
with the eigenvector corrected by the left-out fixed-interface modes, ``y + c``; their
equations at a frequency far below their own give ``c = -K_ii^-1 r_i`` on the interior
(``Phi^T r_i = 0``, so the kept modes' part of ``K_ii^-1`` drops), and the Rayleigh
functional's step is

    delta = sum_h l_{i,h}^H K_ii^-1 r_{i,h} / (z^H Q_r'(lambda) p),

one solve with the interior's stiffness per harmonic and exponent, no factor of the full
lattice. Its size enters each exponent's truncation estimate (``truncation``, times
``TRUNCATION_SAFETY`` in the verdict), so a reduction that is too coarse leaves the verdict
undecided, and :func:`floquet_reduced` raises the cut-off (``CUTOFF_STEPS``) until it
decides.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..harmonics.hill_lattice import LatticeHill
from ..system.periodic import PeriodicSystem
from ..system.reduction import Reduction, craig_bampton
from .result import FloquetResult

__all__ = [
    "CUTOFF_FACTOR",
    "CUTOFF_STEPS",
    "default_cutoff",
    "floquet_reduced",
    "reduction_estimates",
]

#: Default cut-off: this many times the highest frequency of the time variation (the largest
#: coefficient harmonic that is not negligible, :func:`~rheolin.harmonics.lattice.
#: coupling_costs`, times ``w1``): a parametric or combination resonance involves modes up to
#: that frequency, and the modes kept must lie well below the cut-off for the static
#: correction of the estimate to hold (on the finely meshed gearbox, 4 times leaves heavily
#: damped modes near the cut-off undecided, 8 times decides: docs/stability.md, section 9).
CUTOFF_FACTOR = 8.0

#: While the reduction estimate keeps the verdict open, the cut-off is doubled this many times.
CUTOFF_STEPS = 2


def default_cutoff(system: PeriodicSystem) -> float:
    """:data:`CUTOFF_FACTOR` times the highest frequency of the time variation [rad/s]."""
    from ..harmonics.lattice import coupling_costs

    top = max(coupling_costs(system), default=1)
    return float(CUTOFF_FACTOR * top * system.omega)


def floquet_reduced(
    system: PeriodicSystem,
    cutoff: float | None = None,
    *,
    reduction: Reduction | None = None,
    steps: int = CUTOFF_STEPS,
    used: dict[str, Any] | None = None,
    **options: Any,
) -> FloquetResult:
    """The lattice Floquet verdict of ``system`` on its Craig-Bampton reduction with the
    fixed-interface modes up to ``cutoff`` [rad/s] (default :func:`default_cutoff`), each
    exponent's reduction estimate in its truncation estimate; the cut-off doubled up to
    ``steps`` times while that estimate keeps the verdict open. ``reduction``: a basis made
    for another speed of the same model (a map), projected as it is. ``options`` go to
    :func:`rheolin.floquet` (method ``"lattice"``). ``info["reduction"]`` says what was
    kept and the largest estimate; ``used["basis"]`` (when given) is set to the reduction
    the verdict was made on, for the next speed of a map."""
    from .api import floquet

    t0 = time.perf_counter()
    options = {"method": "lattice", **options}
    c = default_cutoff(system) if cutoff is None else float(cutoff)
    tried: list[dict[str, Any]] = []
    res: FloquetResult | None = None
    for step in range(steps + 1):
        if reduction is not None and step == 0:
            red, reduced = reduction, reduction.project(system)
        else:
            red = craig_bampton(system, c)
            reduced = red.system
        res = floquet(reduced, **options)
        delta = reduction_estimates(system, red, reduced, res, budget=options.get("memory_budget"))
        _with_estimates(res, delta)
        tried.append(
            {
                "cutoff": red.cutoff,
                "modes": red.modes,
                "boundary": int(red.boundary.size),
                "dof": reduced.n,
                "next_frequency": red.next_frequency,
                "largest_estimate": float(np.max(np.abs(delta), initial=0.0)),
                "decided": res.decided,
            }
        )
        if res.decided or not _reduction_open(res, delta):
            break
        c = 2.0 * red.cutoff
    assert res is not None
    if used is not None:
        used["basis"] = red
    res.info["reduction"] = {**tried[-1], "tried": tried, "seconds": time.perf_counter() - t0}
    return res


def _with_estimates(res: FloquetResult, delta: np.ndarray) -> None:
    """Add each exponent's reduction estimate to its truncation estimate (and the leading
    exponent's uncertainty)."""
    from .result import TRUNCATION_SAFETY

    mag = np.abs(delta)
    if res.truncation.size == mag.size:
        res.truncation = res.truncation + mag
    unc = res.info.get("uncertainty")
    if isinstance(unc, np.ndarray) and unc.size == mag.size:
        res.info["uncertainty"] = unc + TRUNCATION_SAFETY * mag
    if mag.size:
        res.max_real_uncertainty = float(res.max_real_uncertainty + TRUNCATION_SAFETY * mag[0])
    res.info["reduction_estimate"] = delta


def _reduction_open(res: FloquetResult, delta: np.ndarray) -> bool:
    """Whether the verdict is open by the truncation and reduction estimates of exponents
    whose reduction estimate is a tenth or more of the two (a finer reduction may decide)."""
    rows = res.truncation_open()
    if rows.size != delta.size or not rows.any():
        return False
    share = np.abs(delta[rows]) >= 0.1 * res.truncation[rows]
    return bool(np.any(share))


def reduction_estimates(
    system: PeriodicSystem,
    red: Reduction,
    reduced: PeriodicSystem,
    res: FloquetResult,
    budget: Any = None,
) -> np.ndarray:
    """The reduction estimate ``delta`` (module docstring) of every exponent of ``res``
    (its order), on the lattice of ``res``.

    Only the coefficients with interior rows (or columns) reach the interior residuals:
    the time-averaged ``K_0``, ``D_0``, ``M_0`` and a time variation spread over a body.
    With ``B_t`` their interior rows times ``T`` (``t`` a coefficient ``X_k``) and
    ``B'_t`` their interior columns' adjoint times ``T``, ``delta`` is a bilinear form of
    the reduced vectors through ``G_{t't} = B'_t'^H K_ii^-1 B_t`` (one block solve per
    speed; nothing of full size per exponent)."""
    lam = np.asarray(res.exponents, dtype=complex)
    if lam.size == 0 or res.lattice is None:
        return np.zeros(lam.size, dtype=complex)
    H = np.asarray(res.lattice.indices)
    nh, nr = H.size, reduced.n
    terms = _interior_terms(system, red)
    if not terms:
        return np.zeros(lam.size, dtype=complex)
    _check_memory(red, len(terms), budget)
    G = _coupling_blocks(red, terms)
    small = LatticeHill(reduced, H)
    pos = {int(h): j for j, h in enumerate(H)}
    w = system.omega
    # per pair of terms, the harmonics n of both residuals with z at n + ka and p at n - kb
    # on the lattice (the same for every exponent)
    pairs = []
    for a, (name_a, ka, _, _, _) in enumerate(terms):  # the left residual's coefficient
        for b, (name_b, kb, _, _, _) in enumerate(terms):  # the right residual's
            rows = [
                (i, pos[int(h) + ka], pos[int(h) - kb])
                for i, h in enumerate(H)
                if int(h) + ka in pos and int(h) - kb in pos
            ]
            if rows:
                n_, zi, pi = (np.array(v) for v in zip(*rows, strict=True))
                pairs.append((G[a, b], name_a, name_b, n_, zi, pi))
    out = np.zeros(lam.size, dtype=complex)
    rng = np.random.default_rng(0)
    done: dict[complex, complex] = {}
    for j, x in enumerate(lam):
        twin = _twin(done, complex(x), w)
        if twin is not None:  # a real system's conjugate exponent: the conjugate estimate
            out[j] = np.conj(twin)
            continue
        p, z, den = _null_vectors(small, complex(x), rng)
        if den == 0 or not np.isfinite(den):
            out[j] = np.inf
            continue
        P, Z = p.reshape(nh, nr), z.reshape(nh, nr)
        s = complex(x) + 1j * w * H.astype(float)
        total = 0j
        for Gab, name_a, name_b, n_, zi, pi in pairs:
            coef = _power(name_a, s[n_]) * _power(name_b, s[pi])
            GP = Gab @ P[pi].T  # nr x rows
            total += complex(np.sum(coef * np.sum(np.conj(Z[zi]).T * GP, axis=0)))
        out[j] = total / den
        done[complex(x)] = complex(out[j])
    return out


def _twin(done: dict[complex, complex], x: complex, w: float) -> complex | None:
    """The estimate of the conjugate of ``x`` among those ``done`` (None: not there)."""
    if abs(x.imag) <= 1e-9 * max(abs(x), w):
        return None
    tol = 1e-9 * max(abs(x), w)
    for y, d in done.items():
        if abs(y - np.conj(x)) <= tol:
            return d
    return None


def _coupling_blocks(
    red: Reduction, terms: list[tuple[str, int, str, Any, Any]]
) -> dict[tuple[int, int], np.ndarray]:
    """``G_{ab} = B'_a^H K_ii^-1 B_b`` of the terms, kept on the reduction by the two
    terms' contents: a map's next speed recomputes only the blocks of the coefficients that
    changed (a gyroscopic ``D_0``), and what belongs to no current term is dropped. A
    harmonic ``-k`` whose coefficient is the conjugate of ``k``'s (a real system) takes
    the conjugates of its blocks."""
    cache = red.cache
    digests = {d for _, _, d, _, _ in terms}
    for key in [key for key in cache if key != "T" and not set(key[1:]) <= digests]:
        del cache[key]
    index = {(name, k): j for j, (name, k, _, _, _) in enumerate(terms)}
    mirror = {}  # j -> the term whose conjugate it is
    for j, (name, k, _, B, _) in enumerate(terms):
        i = index.get((name, -k))
        if k < 0 and i is not None and _conjugates(B, terms[i][3]):
            mirror[j] = i
    solved: list[np.ndarray] = [np.zeros(0)] * len(terms)
    for j, (_, _, digest, B, _) in enumerate(terms):
        if j in mirror:
            continue
        key = ("solved", digest)
        if key not in cache:
            cache[key] = _solve(red.interior_lu, B.toarray())
        solved[j] = cache[key]
    for j, i in mirror.items():
        solved[j] = np.conj(solved[i])
    G: dict[tuple[int, int], np.ndarray] = {}
    for a, (_, _, da, _, Bl) in enumerate(terms):
        for b, (_, _, db, _, _) in enumerate(terms):
            if a in mirror or b in mirror:
                continue
            key = ("G", da, db)
            if key not in cache:
                cache[key] = np.asarray(Bl.conj().T @ solved[b])
            G[a, b] = cache[key]
    for a in range(len(terms)):
        for b in range(len(terms)):
            if (a, b) in G:
                continue
            pa, pb = mirror.get(a, a), mirror.get(b, b)
            if (a in mirror) == (b in mirror) and (pa, pb) in G:
                G[a, b] = np.conj(G[pa, pb])  # both conjugated
                continue
            key = ("G", terms[a][2], terms[b][2])
            if key not in cache:
                cache[key] = np.asarray(terms[a][4].conj().T @ solved[b])
            G[a, b] = cache[key]
    return G


def _conjugates(A: Any, B: Any) -> bool:
    """Whether two sparse matrices are each other's conjugates (same pattern)."""
    A, B = sp.csr_array(A), sp.csr_array(B)
    A.sort_indices()
    B.sort_indices()
    return bool(
        A.shape == B.shape
        and np.array_equal(A.indptr, B.indptr)
        and np.array_equal(A.indices, B.indices)
        and np.array_equal(A.data, np.conj(B.data))
    )


def _check_memory(red: Reduction, terms: int, budget: Any) -> None:
    """Refuse (:class:`~rheolin.budget.MemoryBudgetError`) estimates whose interior solves
    (one dense block of the reduced width per coefficient, complex) exceed the budget."""
    from .lattice_run import check_budget

    width = red.T.shape[1]
    need = 2 * terms * red.interior.size * width * 16 + red.T.nbytes
    check_budget(
        need,
        budget,
        f"the reduction estimate ({terms} coefficients x {red.interior.size:,} interior DOFs x "
        f"{width} reduced DOFs)",
        "lower the cut-off",
    )


def _power(name: str, s: np.ndarray) -> np.ndarray:
    """The factor of a coefficient in ``K + s D + s^2 M``."""
    return {"K": np.ones_like(s), "D": s, "M": s * s}[name]


def _interior_terms(system: PeriodicSystem, red: Reduction) -> list[tuple[str, int, str, Any, Any]]:
    """``(name, k, digest, B_t, B'_t)`` of every coefficient with interior rows or columns
    (``digest``: of its contents; ``B``, ``B'`` kept on the reduction by it)."""
    import hashlib

    interior = red.interior
    inside = np.zeros(system.n, dtype=bool)
    inside[interior] = True
    out = []
    for name, table in (("K", system.K), ("D", system.D), ("M", system.M)):
        for k, x in table.items():
            X = sp.csc_array(x) if sp.issparse(x) else sp.csc_array(np.asarray(x))
            X.sort_indices()
            coo = X.tocoo()
            nz = coo.data != 0
            if not (np.any(inside[coo.row[nz]]) or np.any(inside[coo.col[nz]])):
                continue
            h = hashlib.blake2b(digest_size=16)
            for arr in (X.data, X.indices, X.indptr):
                h.update(np.ascontiguousarray(arr).tobytes())
            digest = f"{name}{k}:{h.hexdigest()}"
            key = ("B", digest)
            if key not in red.cache:
                if "T" not in red.cache:
                    red.cache["T"] = sp.csc_array(red.T)
                T = red.cache["T"]  # sparse: a body's DOFs carry its own columns only
                B = sp.csr_array(sp.csr_array(X[interior]) @ T)
                Bl = sp.csr_array(sp.csc_array(X[:, interior]).conj().T @ T)
                red.cache[key] = (B, Bl)
            B, Bl = red.cache[key]
            out.append((name, int(k), digest, B, Bl))
    return out


def _solve(lu: Any, b: np.ndarray) -> np.ndarray:
    """A real factor's solve of real or complex right-hand sides."""
    if not np.iscomplexobj(b):
        return np.asarray(lu.solve(np.ascontiguousarray(b)))
    return np.asarray(lu.solve(np.ascontiguousarray(b.real))) + 1j * np.asarray(
        lu.solve(np.ascontiguousarray(b.imag))
    )


def _null_vectors(
    hill: LatticeHill, lam: complex, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, complex]:
    """Right and left null vectors of the reduced ``Q(lam)`` (inverse iteration on one LU,
    nudged off an exact singularity) and ``z^H Q'(lam) p``."""
    import scipy.sparse.linalg as spla

    scale = max(abs(lam), hill.w)
    for attempt in range(4):
        at = lam + (0 if attempt == 0 else 1e-11 * 10**attempt * scale * (1 + 1j))
        Q = sp.csc_array(hill.Q(at))
        try:
            lu = spla.splu(Q)
            break
        except RuntimeError:  # exactly singular: nudged
            continue
    else:
        return np.zeros(Q.shape[0], complex), np.zeros(Q.shape[0], complex), complex(0)
    size = Q.shape[0]
    p = rng.standard_normal(size) + 1j * rng.standard_normal(size)
    z = rng.standard_normal(size) + 1j * rng.standard_normal(size)
    for _ in range(3):
        p = lu.solve(p)
        p /= np.linalg.norm(p)
        z = lu.solve(z, trans="H")
        z /= np.linalg.norm(z)
    dQ = hill.inner.dQ(lam, hill.w)
    return p, z, complex(np.vdot(z, dQ @ p))
