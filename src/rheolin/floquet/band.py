"""The time-averaged modes in a band, for models too large to decompose densely
(docs/stability.md, section 8).

:class:`BandAveraged` stands for :class:`~rheolin.floquet.averaged.Averaged` in the lattice
search: the modes nearest 0, ``|lambda| <= Omega``, with right and left vectors, by
shift-invert Arnoldi (ARPACK) on the real first-order pencil through one sparse LU of
``K_0``. The modes left out are bounded by :mod:`rheolin.floquet.complement`, which also
enlarges each band mode's Gershgorin radius by its coupling through them.
:func:`band_modes` grows the band until both certificates hold (or the budget ends it).

>>> import numpy as np, rheolin as rl
>>> n = 30
>>> K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
>>> s = rl.PeriodicSystem(1.0, M={0: np.eye(n)}, D={0: 0.02 * np.eye(n)}, K={0: 1e4 * K})
>>> band = BandAveraged(s, 8)
>>> exact = np.linalg.eigvals(np.block([[np.zeros((n, n)), np.eye(n)],
...                                     [-1e4 * K, -0.02 * np.eye(n)]]))
>>> near = exact[np.argsort(np.abs(exact))[:8]]
>>> by_freq = lambda z: z[np.argsort(z.imag)]
>>> bool(np.allclose(by_freq(band.lam), by_freq(near), rtol=1e-10))
True
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..harmonics.hill import state_scaling
from ..system.periodic import PeriodicSystem
from .averaged import MAX_AVERAGED_DENSE, Averaged
from .complement import (
    KAPPA_LIMIT,
    Complement,
    energy_certificate,
    harmonic_dofs,
    touched_dofs,
)
from .result import EPS
from .scan import DENSE_TOUCHED, LOW_RANK, Scan
from .shift_invert import LU_FILL

__all__ = [
    "BAND_ABOVE",
    "BAND_MAX_MODES",
    "BAND_MODES",
    "BandAveraged",
    "band_memory",
    "band_modes",
    "band_vectors",
    "hopeless",
    "time_averaged",
]

#: Systems with ``2 n`` above this take the band (the dense decomposition's limit).
BAND_ABOVE = MAX_AVERAGED_DENSE

#: Modes of the first band; doubled while a certificate fails, up to ``BAND_MAX_MODES``.
BAND_MODES = 40
BAND_MAX_MODES = 320

#: From this many modes on, a certified band is kept while its ``kappa_C`` is below
#: :data:`KEEP_LIMIT` (below that, it doubles above
#: :data:`~rheolin.floquet.complement.KAPPA_LIMIT`): 320 modes of the 19,998-DOF gearbox ran
#: for more than 15 CPU minutes, where the bands of 40 to 160 took 15 s together (their edge
#: falls in the cluster of roots near ``-1/beta`` of its stiffness-proportional damping, where
#: ARPACK stalls: docs/stability.md, 8.2).
BAND_KEEP = 160
KEEP_LIMIT = 0.9

#: ARPACK's relative accuracy of the band's Ritz values.
ARPACK_TOL = 1e-12

#: ARPACK restarts after which a band's run is taken as stalled: its edge then lies inside a
#: cluster of nearly equal roots (the accumulation near ``-1/beta`` of stiffness-proportional
#: damping, ``D = beta K``, one root of every overdamped high mode of a fine mesh), which
#: ARPACK does not converge. The band is then the roots below the cluster: computed again
#: with :data:`STALL_MARGIN` fewer than the stalled run had converged, an edge in the gap
#: below the cluster (docs/stability.md, 8.2). Bands that do not reach a cluster converge in
#: one to three restarts.
BAND_RESTARTS = 10
STALL_MARGIN = 4
STALL_RETRIES = 3


def _parts(system: PeriodicSystem) -> tuple[sp.csc_array, sp.csc_array, sp.csc_array]:
    n = system.n

    def get(table: dict) -> sp.csc_array:
        x = table.get(0)
        return sp.csc_array((n, n)) if x is None else sp.csc_array(x)

    return get(system.K), get(system.D), get(system.M)


class BandAveraged(Averaged):
    """The ``modes`` time-averaged modes nearest 0, balanced like
    :class:`~rheolin.floquet.averaged.Averaged` (``lam``, ``X``, ``W``, ``WB``, ``bound``,
    ``sq``, ``sv``; ``W^H B X = I``). ``complement`` (set by :func:`band_modes`) holds the
    certificates of the modes left out; until then the Gershgorin radii are infinite; ``cpu``
    the CPU seconds of its Arnoldi runs and scans (every band size tried)."""

    partial = True

    def __init__(self, system: PeriodicSystem, modes: int = BAND_MODES) -> None:
        n = system.n
        self.n = n
        self.modal = False
        self.sq, self.sv = sq, sv = state_scaling(system)
        K, D, M = _parts(system)
        k = int(min(modes, 2 * n - 2))
        lam, X, W = _arpack(K, D, M, k, system.omega)
        # balanced: y = (S_q q, S_v v); left vectors w_b = diag(S_q^-1, S_v) w
        S_right = np.concatenate([sq, sv])
        S_left = np.concatenate([1.0 / sq, sv])
        X = S_right[:, None] * X
        W = S_left[:, None] * W
        X = X / np.linalg.norm(X, axis=0)
        Ms = sp.diags_array(1.0 / sv) @ M @ sp.diags_array(1.0 / sv)
        Bb = sp.block_diag([sp.identity(n), Ms], format="csr")
        d = np.einsum("ij,ij->j", W.conj(), Bb @ X)
        ok = np.abs(d) > 1e3 * EPS * np.linalg.norm(W, axis=0)
        self.lam = lam
        self.X = X
        self.W = W / np.where(ok, d, 1.0).conj()
        self.WB = np.asarray((Bb.T @ self.W.conj()).T)  # |band| x 2n: W^H B
        Ks = sp.diags_array(1.0 / sv) @ K @ sp.diags_array(1.0 / sq)
        Ds = sp.diags_array(1.0 / sv) @ D @ sp.diags_array(1.0 / sv)
        normA = max(
            float(np.max(sq / sv)),
            float(abs(Ks).sum(axis=0).max(initial=0.0)),
            float(abs(Ds).sum(axis=0).max(initial=0.0)),
        )
        normB = max(1.0, float(abs(Ms).sum(axis=0).max(initial=0.0)))
        cond = np.linalg.norm(self.W, axis=0)
        self.bound = EPS * (normA + np.abs(lam) * normB) * np.where(ok, cond, np.inf)
        self.radius = float(np.max(np.abs(lam), initial=0.0))
        self.complement: Complement | None = None
        self.cpu: dict[str, float] = {}  # CPU seconds of band_modes' stages
        self.asked = k  # the size asked for (band_modes: before a stall made it smaller)
        self._gershgorin = None

    def gershgorin(self, system: PeriodicSystem, modes: list[int]) -> list[float]:
        """The Gershgorin radii over the band (:meth:`Averaged.gershgorin`) plus each mode's
        coupling through the modes left out, ``beta* p_j`` (docs/stability.md, 8.3);
        infinite while the small-gain bound does not hold."""
        base = super().gershgorin(system, modes)
        c = self.complement
        if c is None or not np.isfinite(c.beta) or c.p.size != self.lam.size:
            return [float("inf")] * len(modes)
        rho = c.rho if c.rho.size == self.lam.size else np.ones(self.lam.size)
        return [
            (r + c.beta * float(c.p[int(m)])) * float(rho[int(m)])
            for r, m in zip(base, modes, strict=True)
        ]


def _arpack(
    K: sp.csc_array, D: sp.csc_array, M: sp.csc_array, k: int, w: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``k`` eigenvalues of ``(A, B) = ([[0, I], [-K, -D]], diag(I, M))`` nearest a real
    shift (0, else ``-w`` when ``K`` is singular), right and left first-order vectors."""
    n = K.shape[0]
    for sigma in (0.0, -w, -10 * w):
        Q = sp.csc_array(K + sigma * D + (sigma * sigma) * M)
        try:
            lu = spla.splu(Q, permc_spec="MMD_AT_PLUS_A")
        except RuntimeError:
            continue
        break
    else:
        raise ValueError("the time-averaged stiffness is singular at every shift tried")
    DM = sp.csc_array(D + sigma * M)
    DMT = sp.csc_array(DM.T)
    MT = sp.csc_array(M.T)

    def op(y: np.ndarray) -> np.ndarray:  # (A - sigma B)^-1 B y
        x = -lu.solve(M @ y[n:] + DM @ y[:n])
        return np.concatenate([x, y[:n] + sigma * x])

    def op_t(y: np.ndarray) -> np.ndarray:  # (A - sigma B)^-T B^T y
        c1, c2 = y[:n], MT @ y[n:]
        b = -lu.solve(c1 + sigma * c2, trans="T")
        return np.concatenate([c2 + DMT @ b, b])

    rng = np.random.default_rng(31)
    v0 = rng.standard_normal(2 * n)
    L = spla.LinearOperator((2 * n, 2 * n), matvec=op, dtype=float)
    theta, X = _below_clusters(L, k, v0)
    kk = int(min(theta.size + 4, 2 * n - 2))
    LT = spla.LinearOperator((2 * n, 2 * n), matvec=op_t, dtype=float)
    theta_t, Y = _below_clusters(LT, kk, v0)  # the roots it misses: by inverse iteration
    lam = sigma + 1.0 / theta
    lam_t = np.conj(sigma + 1.0 / theta_t)  # left vectors belong to conj of the adjoint's
    W = np.zeros_like(X)
    for j, z in enumerate(lam):
        i = int(np.argmin(np.abs(lam_t - z)))
        if abs(lam_t[i] - z) <= 1e-6 * max(abs(z), w):
            W[:, j] = Y[:, i]
        else:  # not among the adjoint's: inverse iteration at the eigenvalue
            W[:, j] = _left_vector(K, D, M, z, X[:, j])
    return lam, X, W


def _below_clusters(L: Any, k: int, v0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The ``k`` eigenpairs of largest modulus of ``L`` by ARPACK; where its run stalls
    (:data:`BAND_RESTARTS`), those below the cluster its edge fell in: the run again with
    :data:`STALL_MARGIN` fewer than it had converged, up to :data:`STALL_RETRIES` times
    (ARPACK's error when the last stalls too, or when fewer than two are left)."""
    size = L.shape[0]

    def run(count: int) -> tuple[np.ndarray, np.ndarray]:
        ncv = int(min(size - 1, max(2 * count + 1, 40)))
        return spla.eigs(
            L, k=count, which="LM", ncv=ncv, tol=ARPACK_TOL, v0=v0, maxiter=BAND_RESTARTS
        )

    count = k
    for _ in range(STALL_RETRIES):
        try:
            return run(count)
        except spla.ArpackNoConvergence as exc:
            fewer = int(exc.eigenvalues.size) - STALL_MARGIN
            if fewer < 2:
                raise
            count = fewer
    return run(count)


def _left_vector(
    K: sp.csc_array, D: sp.csc_array, M: sp.csc_array, lam: complex, x: np.ndarray
) -> np.ndarray:
    """The left first-order vector of ``lam`` by two inverse-iteration steps on the adjoint
    (one complex LU at ``lam``)."""
    n = K.shape[0]
    Q = sp.csc_array(K + lam * D + (lam * lam) * M)
    try:
        lu = spla.splu(Q, permc_spec="MMD_AT_PLUS_A")
    except RuntimeError:
        Q = Q + 1e-12 * abs(Q).max() * sp.identity(n, format="csc")
        lu = spla.splu(Q, permc_spec="MMD_AT_PLUS_A")
    u = np.conj(x[:n]) + 0j
    for _ in range(2):
        u = lu.solve(u, trans="H")
        u /= np.linalg.norm(u)
    # first-order left vector (w_q, w_v) of the pencil from the quadratic one u:
    # w_v = u, w_q = (D + lam M)^H u (the pencil's rows v' = .., M v' = -K q - D v)
    wq = (sp.csc_array(D) + lam * sp.csc_array(M)).conj().T @ u
    return np.concatenate([wq, u])


def band_modes(
    system: PeriodicSystem,
    modes: int | None = None,
    budget: int | None = None,
    start: int | None = None,
    fits: Callable[[BandAveraged], None] | None = None,
) -> BandAveraged:
    """The band of :class:`BandAveraged` with its certificates (``complement``): the energy
    bound at the band's radius and the small-gain scan. Without ``modes`` the band doubles
    from :data:`BAND_MODES` (or from ``start``, the size a nearby speed's certified band was
    asked for) while a certificate fails or ``kappa_C`` exceeds
    :data:`~rheolin.floquet.complement.KAPPA_LIMIT`, up to :data:`BAND_MAX_MODES` (and
    ``budget`` bytes; from :data:`BAND_KEEP` modes on, while it exceeds :data:`KEEP_LIMIT`);
    the last one is returned, its ``complement`` saying what failed, ``asked`` the size it
    was asked for. ``fits(band)`` is called before the scan (the costly part) of a band
    that cannot grow further, and may refuse it: a lattice search that its modes show too
    large for the memory budget is refused before that scan. (Not on a band that may still
    grow: the lattice a band's modes ask for is not monotone in its size; the gearbox of
    50,022 DOF asks for 11 harmonics with 40 modes and 5 with 160.)"""
    if modes is not None:
        k = int(modes)
    elif start is not None:
        k = min(max(int(start), BAND_MODES), BAND_MAX_MODES)
    else:
        k = BAND_MODES
    failed: list[float] = []  # kappa_C of the last bands in a row that failed (>= 1)
    cpu = {"arnoldi": 0.0, "scan": 0.0}  # CPU seconds of every band tried
    previous: BandAveraged | None = None
    while True:
        t = time.process_time()
        band = BandAveraged(system, k)
        cpu["arnoldi"] += time.process_time() - t
        if previous is not None and band.lam.size <= previous.lam.size:
            return previous  # stopped below a cluster no larger than the last band
        band.cpu = cpu
        bigger = 2 * k
        last = (
            modes is not None
            or bigger > min(BAND_MAX_MODES, 2 * system.n - 2)
            or not (budget is None or band_memory(system, bigger) <= budget)
        )
        if fits is not None and last:
            fits(band)
        # a band that will be enlarged anyway once kappa_C passes its limit stops there
        limit = KEEP_LIMIT if k >= BAND_KEEP else KAPPA_LIMIT
        t = time.process_time()
        band.complement = certify(system, band, 1.0 if last else limit)
        cpu["scan"] += time.process_time() - t
        c = band.complement
        if last or (c.certified and c.kappa <= limit and not c.energy_note.startswith("K_s")):
            return band
        if c.kappa >= 1.0:
            failed.append(c.kappa)
            if hopeless(failed):
                return band
        else:  # below 1 but above its limit: hopeless() compares consecutive sizes only
            failed.clear()
        previous, k = band, bigger


def hopeless(failed: list[float]) -> bool:
    """Whether the band stops growing: its last two sizes both failed with
    ``kappa_C >= 1`` and the next, were ``kappa_C`` to shrink by the same factor again,
    would fail too (the modes left out that couple lie far above the band).

    >>> hopeless([9.4, 3.5]), hopeless([9.4, 1.5]), hopeless([3.0])
    (True, False, False)
    """
    if len(failed) < 2:
        return False
    a, b = failed[-2], failed[-1]
    return b * (b / a) >= 1.0


def certify(system: PeriodicSystem, band: BandAveraged, stop: float = 1.0) -> Complement:
    """The small-gain scan up to the pencil's largest frequency (a norm bound), which
    certifies the band, and the energy bound at the band's radius, reported with it (the
    time-averaged eigenvalues of modes the time variation does not touch at all). The scan
    ends at the first point where ``kappa_C >= stop`` (``stop <= 1``); the band is then not
    certified."""
    ok, why = energy_certificate(system, band.radius)
    scan = Scan(system, band)
    out = scan.run(_top_frequency(system, band), min(stop, 1.0))
    out.radius = band.radius
    out.energy, out.energy_note = ok, why
    if not out.complete and out.kappa < 1.0:
        out.certified = False
        out.reason = (
            f"the small-gain bound reached {out.kappa:.3g} at {out.at:.4g} rad/s, above "
            f"{stop:.3g}: a larger band is tried"
        )
    elif not out.kappa < 1.0:
        out.certified = False
        out.reason = (
            f"a mode outside the band couples to the time variation more than its damping "
            f"allows (small-gain bound {out.kappa:.3g} >= 1 at {out.at:.4g} rad/s): more "
            "modes in the band, damping where it is physical, or condensation of that body"
        )
    else:
        out.certified = True
    return out


def _top_frequency(system: PeriodicSystem, band: BandAveraged) -> float:
    """Where the scan ends: ten times the larger of ``sqrt(max K_ii / M_ii)`` and
    ``max D_ii / M_ii``, the band's radius and ``w1``. The diagonal ratios estimate the
    largest undamped frequency and the largest overdamped root from below (Rayleigh
    quotients of unit vectors). On the fine gearbox they are 2 and 4 times below the
    pencil's, and the second (stiffness-proportional damping) sets the end: 140 to 1,100
    times above the largest undamped frequency, where a loop can peak, and 2.5 times above
    the largest overdamped root, a real one, past which the loop is flat (docs/stability.md
    8.3)."""
    K, D, M = _parts(system)
    m = np.abs(M.diagonal())
    m = np.where(m > 0, m, np.inf)
    wk = float(np.sqrt(np.max(np.abs(K.diagonal()) / m, initial=0.0)))
    wd = float(np.max(np.abs(D.diagonal()) / m, initial=0.0))
    return 10.0 * max(wk, wd, band.radius, system.omega)


def band_memory(system: PeriodicSystem, modes: int = BAND_MODES) -> int:
    """Estimated peak memory [bytes] of :func:`band_modes` with ``modes`` modes: the LU of
    ``K_0`` (at the lattice search's fill), the two Arnoldi bases, the band's vectors and the
    scan's factor and transfer blocks (dense up to
    :data:`~rheolin.floquet.scan.DENSE_TOUCHED` touched DOFs, else blocks of the band's
    width, and the energy norm's blocks of that width:
    :class:`~rheolin.floquet.scan.Scan`)."""
    n = system.n
    K, D, M = _parts(system)
    nnz = int((abs(K) + abs(D) + abs(M)).nnz)
    ncv = min(2 * n, max(2 * modes + 9, 40))
    touched = touched_dofs(system).size
    dense = min(touched, DENSE_TOUCHED)
    # blocks of the band's width: the balanced norm's above DENSE_TOUCHED, the energy norm's
    # responses of the band's vectors and their dual norms (scan.Scan) always
    blocks = (4 if touched > DENSE_TOUCHED else 0) * n * modes * 16 + 6 * n * modes * 16
    # the band's left vectors on the DOFs of each harmonic touching many (a flat shaft), twice
    blocks += sum(2 * t * modes * 16 for t in harmonic_dofs(system) if t > LOW_RANK)
    scan = n * dense * 16 + nnz * LU_FILL * 16 + (2 * dense) ** 2 * 16 * 4 + blocks
    return int(
        nnz * LU_FILL * 16 + 2 * (2 * n) * ncv * 8 + band_vectors(system, modes) + scan + 32 * 2**20
    )


def band_vectors(system: PeriodicSystem, modes: int) -> int:
    """Memory [bytes] a band of ``modes`` modes holds while the lattice searches run: its
    right and left vectors and their ``W^H B`` (:class:`BandAveraged`)."""
    return 3 * (2 * system.n) * int(modes) * 16


def time_averaged(
    system: PeriodicSystem, band: int | None = None, budget: int | None = None
) -> Averaged:
    """The time-averaged modes a lattice search starts from: all of them densely
    (:class:`~rheolin.floquet.averaged.Averaged`) up to ``2 n = BAND_ABOVE``, else (or when
    ``band`` modes are asked for) the certified band of :func:`band_modes`."""
    if band is None and 2 * system.n <= BAND_ABOVE:
        return Averaged(system)
    return band_modes(system, band, budget)
