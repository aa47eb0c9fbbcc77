"""The time-averaged modes a lattice search starts from, and the Gershgorin discs of those
modes in the Hill matrix of the infinite lattice."""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..harmonics.hill import dense, scaled_entries, state_scaling
from ..system.periodic import PeriodicSystem
from .result import EPS

__all__ = ["MAX_AVERAGED_DENSE"]


#: Dense eigen-decomposition of the time-averaged pencil up to this size (``2 n``).
MAX_AVERAGED_DENSE = 4000


#: Below this condition number of the balanced ``B`` the pencil is reduced to the standard
#: problem ``B^-1 A``, faster than QZ (bench/stability.py, design notes); above it (massless
#: DOFs: ``B`` singular) QZ keeps the infinite eigenvalues apart.
STANDARD_COND = 1e6


def standard_problem(Ms: np.ndarray) -> bool:
    """Whether a first-order pencil with ``B = diag(I, Ms)`` (balanced) goes to the standard
    problem ``B^-1 A``: ``cond(B)`` at most :data:`STANDARD_COND`.

    >>> standard_problem(np.diag([1.0, 2.0])), standard_problem(np.diag([1.0, 1e-9]))
    (True, False)
    """
    mu = np.linalg.svd(Ms, compute_uv=False) if Ms.size else np.ones(1)
    hi, lo = max(float(mu.max()), 1.0), min(float(mu.min()), 1.0)
    return lo > 0 and hi / lo <= STANDARD_COND


class Averaged:
    """Eigen-decomposition of the time-averaged balanced pencil (first-order, ``2 n``)."""

    def __init__(self, system: PeriodicSystem) -> None:
        n = system.n
        if 2 * n > MAX_AVERAGED_DENSE:
            raise ValueError(
                f"the lattice Floquet method needs the modes of the time-averaged system "
                f"densely (2 n = {2 * n} > {MAX_AVERAGED_DENSE}); reduce the model "
                "(condensed bodies) or give a dense harmonic set with method='sparse'"
            )
        self.sq, self.sv = sq, sv = state_scaling(system)
        Ad, Bd, Ms = averaged_pencil(system, sq, sv)
        standard = standard_problem(Ms)
        known = system.kept("averaged_decomposition")
        if known is not None and standard and Ad.dtype == float:
            lam, X, W = _from_modal(known, sq, sv)
        elif standard:
            # B^-1 A by blocks (B = diag(I, M)); left vectors of the pencil from those of
            # B^-1 A: w^H B^-1 A = lam w^H B^-1
            C = Ad.copy()
            C[n:] = np.linalg.solve(Ms, Ad[n:])
            lam, Y, X = sla.eig(C, left=True, right=True, check_finite=False, overwrite_a=True)
            W = np.array(Y, dtype=complex)
            W[n:] = np.linalg.solve(Ms.conj().T, W[n:])
        else:
            lam, W, X = sla.eig(Ad, Bd, left=True, right=True, check_finite=False)
        finite = np.isfinite(lam)
        self.lam = lam[finite]
        X, W = X[:, finite], W[:, finite]
        X = X / np.linalg.norm(X, axis=0)
        d = np.einsum("ij,ij->j", W.conj(), Bd @ X)
        ok = np.abs(d) > 1e3 * EPS * np.linalg.norm(W, axis=0)
        self.W = W / np.where(ok, d, 1.0).conj()
        self.X = X
        self.WB = self.W.conj().T @ Bd  # modal coordinates of a balanced vector: WB @ y
        # first-order rounding bound of each averaged exponent (huge in a Jordan block, such
        # as the double zero of a free rotation): copies of it scatter by as much
        normA, normB = np.linalg.norm(Ad, 1), np.linalg.norm(Bd, 1)
        cond = np.linalg.norm(self.W, axis=0) / np.maximum(np.abs(d), np.finfo(float).tiny)
        self.bound = EPS * (normA + np.abs(self.lam) * normB) * np.where(ok, cond, np.inf)
        self.modal = bool(ok.all()) and self.lam.size == 2 * n
        self.n = n
        # the balanced couplings of a system and each mode's Gershgorin radius, kept for
        # :meth:`gershgorin` (they do not depend on the lattice: a finer lattice's
        # confirmation asks again for the modes it settles)
        self._gershgorin: tuple[PeriodicSystem, list[tuple[Any, ...]], dict[int, float]] | None
        self._gershgorin = None

    def gershgorin(self, system: PeriodicSystem, modes: list[int]) -> list[float]:
        """Gershgorin radii of time-averaged modes in the modal Hill matrix of the infinite
        lattice: ``sum_k sum_m |w_j^H E_k x_m|`` over every coefficient harmonic ``k`` (rows
        of the balanced first-order coupling in modal coordinates, ``M_k`` at the row's local
        frequency ``lambda_j - i k w1``). Every Hill exponent lies in the union of the discs
        of radius ``R_j`` about the copies ``lambda_j - i h w1``, for any truncation."""
        cache = self._gershgorin
        if cache is None or cache[0] is not system:
            cache = self._gershgorin = (system, _coupling_terms(system, self), {})
        _, terms, known = cache
        missing = sorted({int(m) for m in modes if int(m) not in known})
        if missing:
            # every mode at once on the first call: the searches and their confirmations
            # ask again for the conjugates and the modes of each cluster, and one product
            # over all modes costs less than a few over some
            batch = missing if known else list(range(self.lam.size))
            known.update(zip(batch, _radii(system, self, terms, batch), strict=True))
        return [known[int(m)] for m in modes]


def _from_modal(
    known: tuple[np.ndarray, ...], sq: np.ndarray, sv: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eigenvalues, right and left eigenvectors of the balanced pencil from the decomposition
    a modal solve made of the same time-averaged system (:class:`rheolin.linalg.ModalInverse`:
    ``H = V diag(lam) V^-1`` in ``x = (L_K^T q, L_M^T v)``), without a second eigenvalue
    problem (bench/stability.py, design notes).

    The balanced state ``y = (S_q q, S_v v) = T x`` with ``T = diag(S_q L_K^-T, S_v L_M^-T)``
    has ``B^-1 A = T H T^-1``: right vectors ``T V``, left ones (of ``B^-1 A``) the rows of
    ``V^-1 T^-1``, and the pencil's ``w^H = y^H B^-1`` with ``B^-1 = diag(I, S_v M^-1 S_v)``,
    i.e. ``W^H = [V^-1_q L_K^T S_q^-1, V^-1_v L_M^-1 S_v]``.
    """
    lam, V, Vi, Lk, LkTi, Lmi = known
    n = sq.size
    X = np.concatenate([sq[:, None] * (LkTi @ V[:n]), sv[:, None] * (Lmi.T @ V[n:])])
    WH = np.concatenate([(Vi[:, :n] @ Lk.T) / sq[None, :], (Vi[:, n:] @ Lmi) * sv[None, :]], axis=1)
    return lam, X, WH.conj().T


def averaged_pencil(
    system: PeriodicSystem, sq: np.ndarray, sv: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The balanced time-averaged pencil ``(A, B)`` of :func:`rheolin.harmonics.hill.hill_pencil` on
    harmonic 0, dense, and its mass block: ``A = [[0, S_q S_v^-1], [-K, -D]]``,
    ``B = diag(I, M)`` with ``K = S_v^-1 K_0 S_q^-1``, ``D = S_v^-1 D_0 S_v^-1``,
    ``M = S_v^-1 M_0 S_v^-1``."""
    n = system.n

    def block(table: dict, right: np.ndarray) -> np.ndarray:
        x = table.get(0)
        return np.zeros((n, n)) if x is None else dense(x) / sv[:, None] / right[None, :]

    Ks, Ds, Ms = block(system.K, sq), block(system.D, sv), block(system.M, sv)
    # real coefficients (the usual case): a real eigenproblem, whose complex exponents come
    # in exact conjugate pairs
    dtype = np.result_type(Ks, Ds, Ms, float)
    A = np.zeros((2 * n, 2 * n), dtype=dtype)
    B = np.zeros((2 * n, 2 * n), dtype=dtype)
    A[np.arange(n), n + np.arange(n)] = sq / sv
    A[n:, :n] = -Ks
    A[n:, n:] = -Ds
    B[np.arange(n), np.arange(n)] = 1.0
    B[n:, n:] = Ms
    return A, B, Ms


def _coupling_terms(system: PeriodicSystem, avg: Averaged) -> list[tuple[Any, ...]]:
    """Per coefficient harmonic ``k``: ``(k, *_compact(...))`` of the balanced couplings."""
    iq, iv = 1.0 / avg.sq, 1.0 / avg.sv
    terms = []
    for k in system.coefficient_harmonics:
        mats = [
            None if x is None else scaled_entries(x, iv, right)
            for x, right in ((system.K.get(k), iq), (system.D.get(k), iv), (system.M.get(k), iv))
        ]
        terms.append((k, *_compact(mats)))
    return terms


def _radii(
    system: PeriodicSystem, avg: Averaged, terms: list[tuple[Any, ...]], modes: list[int]
) -> list[float]:
    """The radii of :meth:`Averaged.gershgorin`, computed."""
    n, w = system.n, system.omega
    Wr = avg.W[:, modes].conj().T  # rows of the modal transform
    out = np.zeros(len(modes))
    low = Wr[:, n:]  # the couplings act on the v rows
    for k, rows, cq, cv, Kc, Dc, Mc in terms:
        if rows.size == 0:
            continue
        lr = low[:, rows]
        # the couplings touch a few DOFs (a gear mesh's): only those rows of the modal
        # transform enter, the rest of ``w_j^H E_k`` is zero
        total = np.zeros((len(modes), avg.X.shape[1]), dtype=complex)
        if Kc is not None:
            total += (lr @ Kc) @ avg.X[cq]
        if Dc is not None or Mc is not None:
            pv = lr @ Dc if Dc is not None else 0.0
            if Mc is not None:
                s = avg.lam[modes] - 1j * k * w
                pv = pv + s[:, None] * (lr @ Mc)
            total += pv @ avg.X[n + cv]
        out += np.abs(total).sum(axis=1)
    return out.tolist()


def _compact(mats: list[Any]) -> tuple[Any, ...]:
    """``(rows, q columns, v columns, K, D, M)``: the coupling matrices (entries from
    :func:`~rheolin.harmonics.hill.scaled_entries`, None where absent) as sparse blocks on
    their nonzero rows and columns (K on the q columns, D and M on the v columns). Sparse:
    a flat shaft's twice-per-revolution stiffness touches every node of it, and dense
    blocks of those DOFs grow as their square (0.45 GB at 10,000 DOF)."""
    none = np.zeros(0, dtype=np.int64)
    K, D, M = mats
    rows = np.unique(np.concatenate([a[0] for a in mats if a is not None] + [none]))
    cq = np.unique(K[1]) if K is not None else none
    cv = np.unique(np.concatenate([a[1] for a in (D, M) if a is not None] + [none]))

    def block(a: Any, cols: np.ndarray) -> sp.csr_array | None:
        if a is None:
            return None
        at = (np.searchsorted(rows, a[0]), np.searchsorted(cols, a[1]))
        return sp.csr_array(
            (np.asarray(a[2], dtype=complex), at), shape=(rows.size, cols.size)
        )  # repeated entries summed

    return rows, cq, cv, block(K, cq), block(D, cv), block(M, cv)
