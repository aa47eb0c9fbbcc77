"""The numerical kernel of the lattice search: shifted factors of the lattice operator
``Q(sigma)`` (SuperLU or MKL PARDISO), shift-invert Arnoldi on the balanced first-order
pencil through them, and the Newton polish of an exponent (docs/stability.md).

The first-order pencil is never assembled: :class:`BalancedPencil` applies it, its inverse
and its norms through the second-order operator :class:`~rheolin.harmonics.LatticeHill`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..harmonics.hill_lattice import LatticeHill
from ..linalg.direct import csc_pattern_key

__all__ = ["DGKS", "LU_FILL", "PARDISO_ABOVE", "PARDISO_ABOVE_ARNOLDI", "SPLU"]

#: Estimated LU fill of the lattice operator (entries of the factors / entries of ``Q``).
LU_FILL = 12.0


#: SuperLU options for the lattice operator: ``Q(sigma)`` is structurally symmetric (harmonic
#: ``m`` couples to ``n`` exactly where ``n`` couples to ``m``), so minimum degree on
#: ``A + A^T`` with diagonal pivots (unless one is below 1 % of its column) gives less fill
#: and faster solves than column AMD (bench/stability.py, design notes).
SPLU: dict[str, Any] = {
    "permc_spec": "MMD_AT_PLUS_A",
    "diag_pivot_thresh": 0.01,
    "options": {"SymmetricMode": True},
}


#: Classical Gram-Schmidt is repeated when it cancels more than this fraction of the vector
#: (Daniel, Gragg, Kaufman and Stewart's criterion, 1/sqrt(2)): orthogonal to working
#: precision at half the cost of always orthogonalizing twice.
DGKS = 0.7071


#: Above these many unknowns the lattice operator is factorized by MKL PARDISO where
#: installed (one analysis per lattice serves every shift): a factor used a few times (the
#: polish, a warm-started Arnoldi run) gains from it sooner than one serving the many solves
#: of a cold Arnoldi run; below, SuperLU in the ordering of the lattice's first factor
#: (:class:`Ordered`) is faster (bench/stability.py, design notes).
PARDISO_ABOVE = 20000
PARDISO_ABOVE_ARNOLDI = 30000


def arnoldi(apply: Any, v0: np.ndarray, accept: Any, *, steps: tuple[int, ...], tol: float) -> None:
    """Arnoldi on ``apply`` from ``v0`` (no restarts); at each checkpoint the converged Ritz
    pairs (residual ``<= tol |theta|``) are passed to ``accept(theta, vectors)``, which says
    whether to stop."""
    m_max = steps[-1]
    size = v0.size
    m_max = min(m_max, size)
    V = np.empty((m_max + 1, size), dtype=complex)
    Hm = np.zeros((m_max + 1, m_max), dtype=complex)
    V[0] = v0 / np.linalg.norm(v0)
    checkpoints = {min(s, m_max) for s in steps}
    for j in range(m_max):
        wv = apply(V[j])
        basis = V[: j + 1]
        before = float(np.linalg.norm(wv))
        h = np.conj(basis @ np.conj(wv))
        wv = wv - h @ basis
        beta = float(np.linalg.norm(wv))
        if beta < DGKS * before:  # cancellation: a second Gram-Schmidt pass (DGKS criterion)
            h2 = np.conj(basis @ np.conj(wv))
            wv = wv - h2 @ basis
            h = h + h2
            beta = float(np.linalg.norm(wv))
        Hm[: j + 1, j] = h
        Hm[j + 1, j] = beta
        m = j + 1
        ended = beta <= 1e-14 * float(np.abs(Hm[: j + 2, : j + 1]).max())
        if not ended:
            V[j + 1] = wv / beta
        if m in checkpoints or ended or m == m_max:
            theta, Svec = np.linalg.eig(Hm[:m, :m])
            # the residual of each Ritz pair, also at a breakdown: "ended" is relative to the
            # largest Ritz value, and a shift on an exponent (a tracked start) makes that one
            # huge while the far pairs are not converged at all
            res = beta * np.abs(Svec[-1, :])
            good = res <= tol * np.abs(theta)
            if good.any():
                vecs = V[:m].T @ Svec[:, good]
                if accept(theta[good], vecs) or ended:
                    return
            if ended:
                return


class Ordered:
    """The minimum-degree ordering of a lattice's ``Q`` pattern, found by its first SuperLU
    factorization and reused for every later shift (the pattern does not change with the
    shift): the symmetrically permuted ``Q[p][:, p]`` is factorized in its natural order,
    which saves the ordering (half of SuperLU's time on an order-1 gearbox lattice, a
    quarter on order 2) and gives the same factors (bench/stability.py, design notes)."""

    def __init__(self, Q: sp.csc_array, perm_c: np.ndarray) -> None:
        self.p = np.argsort(perm_c)  # Q[p][:, p] has SuperLU's fill in its natural order
        self.key = csc_pattern_key(Q.indptr, Q.indices)
        marks = sp.csc_array(
            (np.arange(1, Q.nnz + 1, dtype=float), Q.indices, Q.indptr), shape=Q.shape
        )
        permuted = sp.csc_array(marks[self.p][:, self.p])
        permuted.sort_indices()
        self.gather = permuted.data.astype(np.int64) - 1  # permuted.data = Q.data[gather]
        self.indices, self.indptr = permuted.indices, permuted.indptr

    def matches(self, Q: sp.csc_array) -> bool:
        return csc_pattern_key(Q.indptr, Q.indices) == self.key

    def factor(self, Q: sp.csc_array) -> OrderedLU:
        return self.factor_values(Q.data)

    def factor_values(self, data: np.ndarray) -> OrderedLU:
        """The factor of the matrix of this pattern with the values ``data`` (in its CSC
        order)."""
        size = self.p.size
        B = sp.csc_array((data[self.gather], self.indices, self.indptr), shape=(size, size))
        opts = {**SPLU, "permc_spec": "NATURAL"}
        return OrderedLU(spla.splu(B, **opts), self.p)


class OrderedLU:
    """A SuperLU factor of ``Q[p][:, p]`` that solves with ``Q``."""

    def __init__(self, lu: Any, p: np.ndarray) -> None:
        self.lu, self.p = lu, p

    def solve(self, b: np.ndarray, trans: str = "N") -> np.ndarray:
        y = self.lu.solve(np.ascontiguousarray(b[self.p]), trans=trans)
        x = np.empty_like(y)
        x[self.p] = y
        return x


class PatternLU:
    """SuperLU factors of matrices that share one pattern: the first with minimum degree,
    the next ones in its ordering (:class:`Ordered`)."""

    def __init__(self) -> None:
        self.ordered: Ordered | None = None

    def __call__(self, Q: sp.csc_array) -> Any:
        if self.ordered is not None and self.ordered.matches(Q):
            return self.ordered.factor(Q)
        lu = spla.splu(Q, **SPLU)
        self.ordered = Ordered(Q, lu.perm_c)
        return lu

    def pattern(self, data: np.ndarray, indices: np.ndarray, indptr: np.ndarray) -> Any:
        """The factor of the CSC matrix ``(data, indices, indptr)`` whose pattern stays the
        same from call to call (the caller's promise: it is not compared, and the matrix is
        built only for the first factor, whose ordering the others reuse)."""
        if self.ordered is None:
            size = indptr.size - 1
            return self(sp.csc_array((data, indices, indptr), shape=(size, size)))
        return self.ordered.factor_values(data)


def superlu(hill: LatticeHill, Q: sp.csc_array) -> Any:
    """SuperLU of ``Q`` on ``hill``'s lattice (:class:`PatternLU`, kept with the lattice)."""
    if hill._ordered is None:
        hill._ordered = PatternLU()
    return hill._ordered(Q)


class Shifted:
    """A sparse LU of ``Q(sigma)`` that remembers its (possibly nudged) shift."""

    def __init__(self, lu: Any, sigma: complex, Q: Any = None) -> None:
        self.lu = lu
        self.sigma = sigma
        self.Q = Q  # the matrix factorized

    def solve(self, b: np.ndarray, trans: str = "N") -> np.ndarray:
        return np.asarray(self.lu.solve(b, trans=trans))


def pardiso_factor(hill: LatticeHill, Q: Any) -> Any | None:
    """A PARDISO factor of ``Q`` (None: not installed, or no free slot), from the analysis
    ``hill`` keeps for its pattern (:meth:`~rheolin.harmonics.LatticeHill.pardiso_analysis`)."""
    from ..linalg.direct import available_backends

    if "pardiso" not in available_backends():
        return None
    Q = sp.csc_array(Q)
    Q.sort_indices()
    analysis = hill.pardiso_analysis(Q, slots=16, refinement=0)
    try:
        return analysis.factor(Q.data)
    except RuntimeError as exc:
        if "slots" in str(exc):
            return None
        raise


def factor(hill: LatticeHill, sigma: complex, w: float, *, many: bool = False) -> Shifted:
    """LU of ``Q(sigma)``; an exactly singular shift is moved slightly. ``many``: the factor
    will serve many solves (an Arnoldi run), which changes the fastest backend."""
    scale = max(abs(sigma), w)
    if abs(sigma) < 1e-9 * w:
        sigma = complex(1e-4 * w, 1e-4 * w)
    for attempt in range(4):
        Q = hill.Q(sigma)
        try:
            if Q.shape[0] > (PARDISO_ABOVE_ARNOLDI if many else PARDISO_ABOVE):
                f = pardiso_factor(hill, Q)
                if f is not None:
                    return Shifted(f, sigma, Q)
            return Shifted(superlu(hill, Q), sigma, Q)
        except RuntimeError:  # exactly singular
            sigma += 1e-7 * scale * (1 + 1j) * 10**attempt
    raise RuntimeError(f"cannot factorize the lattice Hill operator near {sigma}")


def polish(
    hill: LatticeHill, lam: complex, q: np.ndarray, w: float, step: float | None = None
) -> tuple[complex, np.ndarray, np.ndarray, np.ndarray]:
    """One LU at the exponent: inverse iteration for the right and left null vectors of
    ``Q(lam)`` and a two-sided Newton (Rayleigh functional) step on ``lam``.

    (Reusing the search's factor at ``sigma`` instead, with shift-invert steps of the
    first-order pencil, gives the same vectors but takes 5-13 steps where one LU and three
    solves do, and the kept factors cost memory.)

    The Newton step is taken when it is below ``step`` (default ``1e-4 max(|lam|, w1)``: a
    polish of a converged pair; a tracked exponent allows larger ones).

    Returns ``(lam, q, u, P(lam)^H u)``.
    """
    lu = factor(hill, lam, w)
    dQ = hill.inner.dQ(lam, w)
    dQH = dQ.conj().T
    q1 = lu.solve(np.asarray(dQ @ q))
    q1 /= np.linalg.norm(q1)
    u = lu.solve(np.asarray(dQH @ q1), trans="H")  # a start for the left vector
    u /= np.linalg.norm(u)
    u = lu.solve(np.asarray(dQH @ u), trans="H")
    u /= np.linalg.norm(u)
    Q = lu.Q if lu.sigma == lam else hill.Q(lam)
    num = np.vdot(u, Q @ q1)
    den = np.vdot(u, dQ @ q1)
    limit = 1e-4 * max(abs(lam), w) if step is None else step
    if den != 0 and np.isfinite(num / den) and abs(num / den) < limit:
        lam = lam - num / den
    P = hill.inner.P(lam, w)
    return complex(lam), q1, u, np.conj(np.asarray(P.T @ np.conj(u)))


def pencil_norms(hill: LatticeHill, sq: np.ndarray, sv: np.ndarray) -> tuple[float, float]:
    """1-norms of the balanced first-order Hill pencil ``(A, B)`` of
    :func:`~rheolin.harmonics.hill_pencil` on the lattice, from the couplings of ``hill`` (column
    sums; without building the pencil).

    Columns of harmonic ``h``: ``q`` columns ``|w h| + sum |K| / (s_v,row s_q,col)``, ``v``
    columns ``s_q / s_v + sum |D + i h w M| / (s_v,row s_v,col)``; ``B``: 1 on ``q``
    columns and ``sum |M| / (s_v,row s_v,col)`` on ``v`` columns.
    """
    inner, n, w = hill.inner, hill.n, hill.w
    size = hill.size
    dof_r, dof_c = inner.rows % n, inner.cols % n
    col_q = np.abs(w * np.repeat(hill.H.astype(float), n))
    col_v = np.tile(sq / sv, hill.H.size)
    b_v: np.ndarray = np.zeros(size)
    if inner.nnz:
        col_q = col_q + np.bincount(
            inner.cols, np.abs(inner.K) / (sv[dof_r] * sq[dof_c]), minlength=size
        )
        col_v = col_v + np.bincount(
            inner.cols,
            np.abs(inner.D + 1j * w * inner.col_h * inner.M) / (sv[dof_r] * sv[dof_c]),
            minlength=size,
        )
        b_v = np.bincount(inner.cols, np.abs(inner.M) / (sv[dof_r] * sv[dof_c]), minlength=size)
    normA = float(max(col_q.max(initial=0.0), col_v.max(initial=0.0)))
    normB = float(max(1.0, b_v.max(initial=0.0)))
    return normA, normB


def harmonic_energy(y: np.ndarray, n: int, nh: int) -> np.ndarray:
    """Energy ``|q|^2 + |v|^2`` of the first-order vector ``y`` (``n`` DOFs on ``nh``
    harmonics) per harmonic."""
    with np.errstate(under="ignore"):
        e2 = np.abs(y) ** 2
    return np.asarray(
        e2[: n * nh].reshape(nh, n).sum(axis=1) + e2[n * nh :].reshape(nh, n).sum(axis=1)
    )


def harmonic_block(y: np.ndarray, i: int, n: int, nh: int) -> np.ndarray:
    """The ``(q, v)`` block of the first-order vector ``y`` (``n`` DOFs on ``nh`` harmonics)
    at harmonic position ``i``."""
    return np.concatenate([y[i * n : (i + 1) * n], y[n * nh + i * n : n * nh + (i + 1) * n]])


class BalancedPencil:
    """The balanced first-order Hill pencil ``(A, B)`` on a lattice (:func:`~rheolin.harmonics.
    hill_pencil`'s, with the state scaling ``sq``, ``sv``), applied through the second-order
    operator ``hill``: its vectors ``y = (s_q q, s_v v)`` over the harmonics, residuals, ``B``
    and 1-norms."""

    def __init__(self, hill: LatticeHill, sq: np.ndarray, sv: np.ndarray) -> None:
        self.hill = hill
        nh = hill.H.size
        self.half = hill.n * nh  # the q part of a first-order vector
        self.sq, self.sv = np.tile(sq, nh), np.tile(sv, nh)
        self.Mconv = hill.inner.Mconv()
        self.normA, self.normB = pencil_norms(hill, sq, sv)
        self._Mb: Any = None

    def unbalanced(self, yb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(q, v)`` of a balanced first-order vector."""
        return yb[: self.half] / self.sq, yb[self.half :] / self.sv

    def first_order(self, q: np.ndarray, lam: complex) -> np.ndarray:
        """The balanced first-order right vector ``(q, s q)`` of ``q``."""
        return np.concatenate([q * self.sq, self.hill.s(lam) * q * self.sv])

    def residual(self, q: np.ndarray, lam: complex) -> float:
        """``||Q(lam) q||`` on the balanced rows (the first-order pencil's residual)."""
        return float(np.linalg.norm(np.asarray(self.hill.Q(lam) @ q) / self.sv))

    def B(self, xb: np.ndarray) -> np.ndarray:
        """The balanced first-order ``B`` times ``xb``."""
        if self._Mb is None:
            scale = sp.diags_array(1.0 / self.sv)
            self._Mb = scale @ self.Mconv @ scale
        return np.concatenate([xb[: self.half], self._Mb @ xb[self.half :]])


class ShiftInvert:
    """The balanced ``(A - sigma B)^-1 B`` of a :class:`BalancedPencil`, one solve with the
    factor ``lu`` of ``Q(sigma)`` per application."""

    def __init__(self, pencil: BalancedPencil, lu: Shifted) -> None:
        hill = pencil.hill
        self.pencil, self.lu = pencil, lu
        self.P = hill.inner.P(lu.sigma, hill.w)
        self.S = hill.s(lu.sigma)

    def __call__(self, yb: np.ndarray) -> np.ndarray:
        pencil = self.pencil
        xq, xv = pencil.unbalanced(yb)
        q = -self.lu.solve(np.asarray(pencil.Mconv @ xv + self.P @ xq))
        return np.concatenate([q * pencil.sq, (xq + self.S * q) * pencil.sv])
