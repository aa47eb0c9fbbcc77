"""Floquet stability of the periodic system by Hill's method (DESIGN.md §6)."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .harmonics import HarmonicSet, as_harmonic_set
from .system import PeriodicSystem

__all__ = ["FloquetResult", "floquet", "hill_matrices"]

#: Dense Hill matrices beyond this size are refused (sparse shift-invert is the way there).
MAX_DENSE_HILL = 6000


@dataclass
class FloquetResult:
    """Floquet exponents of the homogeneous system ``M q'' + D q' + K q = 0``.

    Attributes
    ----------
    exponents
        One representative per exponent (``2 n`` of them for a nonsingular ``M_0``),
        imaginary part in ``(-omega/2, omega/2]``, sorted by decreasing real part.
    max_real
        Largest real part [1/s].
    stable
        True when no exponent has a positive real part beyond round-off (``max_real <= tol``).
    marginal
        True when the largest real part is zero within ``tol`` (undamped, bounded motion).
    tol
        Round-off bound used for the decision.
    omega
        Base angular frequency of the system.
    """

    exponents: np.ndarray
    max_real: float
    stable: bool
    marginal: bool
    tol: float
    omega: float


def _dense(x: Any) -> np.ndarray:
    return x.toarray() if sp.issparse(x) else np.asarray(x)


def hill_matrices(system: PeriodicSystem, harmonics: HarmonicSet) -> tuple[np.ndarray, ...]:
    """Dense Hill pencil ``(A, B)``: ``lambda B z = A z`` with ``z = (q_n, v_n)_n``.

    With ``q(t) = exp(lambda t) sum_n q_n exp(i n w1 t)`` and ``v_n = (lambda + i n w1) q_n``::

        lambda q_m               = v_m - i m w1 q_m
        lambda sum_n M_{m-n} v_n = -sum_n (K_{m-n} q_n + (D_{m-n} + i n w1 M_{m-n}) v_n)
    """
    H = harmonics.indices
    n, w = system.n, system.omega
    size = 2 * n * H.size
    A = np.zeros((size, size), dtype=complex)
    B = np.zeros((size, size), dtype=complex)
    blocks = {
        name: {k: _dense(x) for k, x in table.items()}
        for name, table in (("M", system.M), ("D", system.D), ("K", system.K))
    }
    eye = np.eye(n)
    for i, m in enumerate(H):
        rq = slice(2 * n * i, 2 * n * i + n)
        rv = slice(2 * n * i + n, 2 * n * (i + 1))
        A[rq, rq] = -1j * m * w * eye
        A[rq, rv] = eye
        B[rq, rq] = eye
        for j, nn in enumerate(H):
            k = int(m - nn)
            cq = slice(2 * n * j, 2 * n * j + n)
            cv = slice(2 * n * j + n, 2 * n * (j + 1))
            Mk = blocks["M"].get(k)
            Dk = blocks["D"].get(k)
            Kk = blocks["K"].get(k)
            if Kk is not None:
                A[rv, cq] -= Kk
            if Dk is not None:
                A[rv, cv] -= Dk
            if Mk is not None:
                A[rv, cv] -= 1j * nn * w * Mk
                B[rv, cv] += Mk
    return A, B


def floquet(system: PeriodicSystem, harmonics: HarmonicSet | int | Iterable[int]) -> FloquetResult:
    """Floquet exponents by Hill's method.

    The truncated Hill pencil has ``|H|`` copies of every exponent, shifted by ``i k w1``;
    the representative kept is the eigenvalue whose eigenvector is centred on harmonic 0
    (smallest energy-weighted mean harmonic), folded into ``(-w1/2, w1/2]``.

    Parameters
    ----------
    system
        The periodic system (the load is ignored).
    harmonics
        Harmonic set for the Hill truncation: an int ``N`` means ``-N..N``. Use a dense
        set: Floquet modes are not restricted to the load's harmonics.

    Examples
    --------
    Mathieu's equation ``y'' + (a - 2 q cos 2t) y = 0`` at ``a = 1, q = 0.2`` lies inside the
    first instability band ``(b_1, a_1)``:

    >>> import numpy as np, rheolin as rl
    >>> s = rl.PeriodicSystem(2.0, M={0: np.eye(1)}, K={0: np.eye(1), 1: -0.2 * np.eye(1)})
    >>> res = rl.floquet(s, 10)
    >>> res.stable, len(res.exponents)
    (False, 2)
    """
    hset = as_harmonic_set(harmonics)
    size = 2 * system.n * len(hset)
    if size > MAX_DENSE_HILL:
        raise ValueError(
            f"the dense Hill matrix would have size {size} (2 x n x |H|) > {MAX_DENSE_HILL}; "
            "reduce `harmonics` or the model size"
        )
    A, B = hill_matrices(system, hset)
    lam, vecs = sla.eig(A, B, check_finite=False)
    finite = np.isfinite(lam)
    lam, vecs = lam[finite], vecs[:, finite]
    H = hset.indices.astype(float)
    n = system.n
    energy = np.abs(vecs) ** 2
    per_h = energy.reshape(len(H), 2 * n, -1).sum(axis=1)  # (|H|, n_eig)
    per_h /= per_h.sum(axis=0, keepdims=True)
    centroid = H @ per_h
    w = system.omega
    expected = 2 * n - _massless_count(system)
    order = np.argsort(np.abs(centroid), kind="stable")
    chosen = lam[order[:expected]]
    # fold the imaginary part into (-w/2, w/2]
    shift = np.ceil(chosen.imag / w - 0.5)
    reps = chosen - 1j * w * shift
    reps = reps[np.argsort(-reps.real, kind="stable")]
    scale = max(float(np.max(np.abs(reps))) if reps.size else 0.0, w)
    tol = 1e-9 * scale
    max_real = float(reps.real.max()) if reps.size else float("-inf")
    return FloquetResult(
        exponents=reps,
        max_real=max_real,
        stable=bool(max_real <= tol),
        marginal=bool(abs(max_real) <= tol),
        tol=tol,
        omega=w,
    )


def _massless_count(system: PeriodicSystem) -> int:
    """Rank deficiency of ``M_0`` (DOFs without inertia have no oscillatory exponents)."""
    M0 = system.M.get(0)
    if M0 is None:
        return system.n
    s = np.linalg.svd(_dense(M0), compute_uv=False)
    return int(np.sum(s <= 1e-12 * s.max())) if s.size and s.max() > 0 else system.n
