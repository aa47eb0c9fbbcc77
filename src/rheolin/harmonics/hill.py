"""The Hill pencil of a periodic system: Floquet exponents as a generalized eigenproblem.

With ``q(t) = exp(lambda t) sum_n q_n exp(i n w1 t)`` the homogeneous system becomes the
pencil ``lambda B y = A y`` over the harmonics of a truncation; :func:`state_scaling`
balances it so that stiff and soft parts of a model have comparable entries.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..system.periodic import PeriodicSystem
from .sets import HarmonicSet, as_harmonic_set

__all__ = ["hill_matrices", "hill_pencil", "state_scaling"]


def dense(x: Any) -> np.ndarray:
    return x.toarray() if sp.issparse(x) else np.asarray(x)


def scaled_entries(x: Any, left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, ...]:
    """The nonzero entries ``(rows, cols, values)`` of ``diag(left) x diag(right)`` (``x``
    dense or sparse)."""
    if sp.issparse(x):
        coo = sp.coo_array(x)
        r, c, v = coo.row, coo.col, coo.data
    else:
        x = np.asarray(x)
        r, c = np.nonzero(x)
        v = x[r, c]
    keep = v != 0
    r, c = r[keep].astype(np.int64), c[keep].astype(np.int64)
    return r, c, v[keep] * left[r] * right[c]


def diag(x: Any, n: int) -> np.ndarray:
    if x is None:
        return np.zeros(n)
    return np.abs(np.asarray(x.diagonal() if sp.issparse(x) else np.diagonal(x), dtype=float))


def state_scaling(system: PeriodicSystem) -> tuple[np.ndarray, np.ndarray]:
    """Scale factors ``(s_q, s_v)`` that balance the first-order state.

    ``y_q = s_q q``, ``y_v = s_v v`` with ``s_q = sqrt(|K0_ii|)`` and ``s_v = sqrt(|M0_ii|)``,
    so both halves of the state carry energy-like units and the balanced coefficients
    ``S_v^-1 K S_q^-1``, ``S_v^-1 M S_v^-1`` are of the order of frequencies and 1.
    DOFs without stiffness use ``sqrt(m) w1``, DOFs without mass ``sqrt(k) / w1``.

    >>> import numpy as np, rheolin as rl
    >>> s = rl.PeriodicSystem(1.0, M={0: np.diag([1.0, 4.0])}, K={0: np.diag([1e12, 9.0])})
    >>> state_scaling(s)
    (array([1.e+06, 3.e+00]), array([1., 2.]))
    """
    n, w = system.n, system.omega
    m = diag(system.M.get(0), n)
    k = diag(system.K.get(0), n)
    sq = np.sqrt(np.where(k > 0, k, np.where(m > 0, m * w * w, 1.0)))
    sv = np.where(m > 0, np.sqrt(m), sq / w)
    return sq, sv


def hill_pencil(
    system: PeriodicSystem, harmonics: HarmonicSet | int | Iterable[int], *, balance: bool = True
) -> tuple[sp.csc_array, sp.csc_array]:
    """Sparse Hill pencil ``(A, B)``: ``lambda B y = A y`` with ``y = (s_q q_n, s_v v_n)_n``.

    With ``q(t) = exp(lambda t) sum_n q_n exp(i n w1 t)`` and ``v_n = (lambda + i n w1) q_n``::

        lambda q_m               = v_m - i m w1 q_m
        lambda sum_n M_{m-n} v_n = -sum_n (K_{m-n} q_n + (D_{m-n} + i n w1 M_{m-n}) v_n)

    ``balance=True`` applies the similarity scaling of :func:`state_scaling` (eigenvalues are
    unchanged). Block ``i`` (harmonic ``H[i]``) holds rows ``2 n i .. 2 n (i + 1)``.

    >>> import numpy as np, rheolin as rl
    >>> s = rl.PeriodicSystem(2.0, M={0: np.eye(1)}, K={0: np.eye(1), 1: -0.2 * np.eye(1)})
    >>> A, B = hill_pencil(s, 1)
    >>> A.shape, B.nnz
    ((6, 6), 6)
    """
    hset = as_harmonic_set(harmonics)
    H = hset.indices
    n, w = system.n, system.omega
    if balance:
        sq, sv = state_scaling(system)
    else:
        sq, sv = np.ones(n), np.ones(n)
    Tq, Tv = sp.diags_array(1.0 / sq), sp.diags_array(1.0 / sv)

    def scaled(table: dict[int, Any], right: Any) -> dict[int, sp.csr_array]:
        return {k: sp.csr_array(Tv @ sp.csr_array(x) @ right) for k, x in table.items()}

    Ms, Ds, Ks = scaled(system.M, Tv), scaled(system.D, Tv), scaled(system.K, Tq)
    eye = sp.identity(n, dtype=complex, format="csr")
    coupling = sp.diags_array((sq / sv).astype(complex))
    top = sp.csr_array(([1.0], ([0], [0])), shape=(2, 2))  # the (q, q) quadrant
    low = sp.csr_array(([1.0], ([1], [1])), shape=(2, 2))  # the (v, v) quadrant
    lq = sp.csr_array(([1.0], ([1], [0])), shape=(2, 2))  # the (v, q) quadrant
    hq = sp.csr_array(([1.0], ([0], [1])), shape=(2, 2))  # the (q, v) quadrant
    Hf = H.astype(float)
    A = sp.kron(sp.diags_array(-1j * w * Hf), sp.kron(top, eye)) + sp.kron(
        sp.identity(H.size), sp.kron(hq, coupling)
    )
    B = sp.kron(sp.identity(H.size), sp.kron(top, eye))
    for k in set(Ms) | set(Ds) | set(Ks):
        # shift[i, j] = 1 where H[i] - H[j] == k: row harmonic m couples to column m - k
        # (sorted search: linear in |H|, never an |H| x |H| comparison)
        cols = np.arange(H.size)
        pos = np.minimum(np.searchsorted(H, H + k), H.size - 1)
        hit = H[pos] == H + k
        rows, cols = pos[hit], cols[hit]
        if rows.size == 0:
            continue
        shift = sp.csr_array((np.ones(rows.size), (rows, cols)), shape=(H.size, H.size))
        if k in Ks:
            A = A - sp.kron(shift, sp.kron(lq, Ks[k]))
        if k in Ds:
            A = A - sp.kron(shift, sp.kron(low, Ds[k]))
        if k in Ms:
            # the column harmonic n = H[j] multiplies M_{m-n}
            A = A - sp.kron(shift @ sp.diags_array(1j * w * Hf), sp.kron(low, Ms[k]))
            B = B + sp.kron(shift, sp.kron(low, Ms[k]))
    A = sp.csc_array(A, dtype=complex)
    B = sp.csc_array(B, dtype=complex)
    A.eliminate_zeros()
    B.eliminate_zeros()
    return sp.csc_array(A), sp.csc_array(B)


def hill_matrices(system: PeriodicSystem, harmonics: HarmonicSet) -> tuple[np.ndarray, ...]:
    """Dense, unbalanced Hill pencil ``(A, B)``: ``lambda B z = A z``, ``z = (q_n, v_n)_n``.

    See :func:`hill_pencil` for the equations; kept for small systems and tests.
    """
    A, B = hill_pencil(system, harmonics, balance=False)
    return A.toarray(), B.toarray()
