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
    tq, tv = 1.0 / sq, 1.0 / sv
    nh = H.size
    Hf = H.astype(float)
    spin = 1j * w * Hf  # i n w1 of each harmonic
    base = 2 * n * np.arange(nh, dtype=np.int64)  # first row of each harmonic's block
    a = np.arange(n, dtype=np.int64)
    # per harmonic: -i n w1 on the (q, q) diagonal and the balanced identity sq / sv in (q, v)
    rows = [(base[:, None] + a).ravel(), (base[:, None] + a).ravel()]
    cols = [(base[:, None] + a).ravel(), (base[:, None] + n + a).ravel()]
    vals = [np.repeat(-spin, n), np.tile((sq / sv).astype(complex), nh)]
    brows, bcols = [(base[:, None] + a).ravel()], [(base[:, None] + a).ravel()]
    bvals = [np.ones(nh * n, dtype=complex)]
    tables = (system.K, system.D, system.M)
    for k in sorted(set().union(*tables)):
        # row harmonic m couples to column m - k (sorted search: linear in |H|)
        col_h = np.arange(nh)
        pos = np.minimum(np.searchsorted(H, H + k), nh - 1)
        hit = H[pos] == H + k
        row_h, col_h = pos[hit], col_h[hit]
        if row_h.size == 0:
            continue
        r0 = (base[row_h] + n)[:, None]  # the v rows of the row harmonic
        for table, right, into_v in ((system.K, tq, False), (system.D, tv, True)):
            if k in table:
                r, c, v = scaled_entries(table[k], tv, right)
                rows.append((r0 + r).ravel())
                cols.append((base[col_h][:, None] + (n if into_v else 0) + c).ravel())
                vals.append(np.broadcast_to(-v.astype(complex), (row_h.size, v.size)).ravel())
        if k in system.M:
            r, c, v = scaled_entries(system.M[k], tv, tv)
            vr, vc = (r0 + r).ravel(), (base[col_h][:, None] + n + c).ravel()
            # the column harmonic n = H[j] multiplies M_{m-n}
            rows.append(vr)
            cols.append(vc)
            vals.append((-(spin[col_h][:, None] * v)).ravel())
            brows.append(vr)
            bcols.append(vc)
            bvals.append(np.broadcast_to(v.astype(complex), (row_h.size, v.size)).ravel())
    size = 2 * n * nh

    def assemble(r: list[np.ndarray], c: list[np.ndarray], v: list[np.ndarray]) -> sp.csc_array:
        out = sp.csc_array(
            (np.concatenate(v), (np.concatenate(r), np.concatenate(c))), shape=(size, size)
        )
        out.sum_duplicates()
        out.eliminate_zeros()
        return out

    return assemble(rows, cols, vals), assemble(brows, bcols, bvals)


def hill_matrices(system: PeriodicSystem, harmonics: HarmonicSet) -> tuple[np.ndarray, ...]:
    """Dense, unbalanced Hill pencil ``(A, B)``: ``lambda B z = A z``, ``z = (q_n, v_n)_n``.

    See :func:`hill_pencil` for the equations; kept for small systems and tests.
    """
    A, B = hill_pencil(system, harmonics, balance=False)
    return A.toarray(), B.toarray()
