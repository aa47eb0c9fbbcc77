"""The small-gain scan of the modes a band leaves out (docs/stability.md, 8.3):
``kappa_C(i omega) = sum_k ||G_C E_k||`` and the band modes' coupling through them ``q_S``,
point by point on :mod:`~rheolin.floquet.scan_grid`'s frequencies, in the energy norm of the
frequency (:mod:`~rheolin.floquet.energy_norm`) and in the balanced state's norm at the
touched DOFs; :class:`Scan` returns the :class:`~rheolin.floquet.complement.Complement` of the
norm that bounds it better.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..system.periodic import PeriodicSystem
from .complement import Complement, averaged_part, nonzero_dofs, touched_dofs
from .energy_norm import (
    SAME_INPUT,
    EnergyFamily,
    apply_norm,
    column_energies,
    norm_in,
)
from .scan_grid import QUIET, SPACING, scan_grid, visiting_order
from .shift_invert import PatternLU

__all__ = ["DENSE_TOUCHED", "LOW_RANK", "NORM_STEPS", "SPLIT", "Scan"]

#: Power-iteration steps for a norm when the touched DOFs are too many for dense blocks.
NORM_STEPS = 12

#: Touched DOFs up to this many are handled as dense blocks; above, by operators.
DENSE_TOUCHED = 400

#: The band's part of the transfer function is taken with its ``1/s`` tail removed,
#: ``x_j w_j^H (1/(s - lambda_j) - 1/(s - sigma))``, ``sigma = -SPLIT radius`` (the rest then
#: decays as ``1/s^2``, as a second-order transfer function does; the band's Gershgorin radii
#: grow by ``|lambda_j - sigma| / |sigma|``, within 1e-3 of 1 here).
SPLIT = 30.0

#: A coefficient harmonic touching up to this many DOFs has its loop gain in the energy norm
#: exactly, from one block solve per point (a gear mesh's few DOFs); above, by Lanczos (a flat
#: shaft).
LOW_RANK = 96


def _norm2(apply: Any, adjoint: Any, dim: int, rng: np.random.Generator) -> float:
    """The 2-norm of an operator by power iteration on ``A^H A`` (an estimate from below,
    converged to about 1e-3 in a dozen steps on these transfer functions)."""
    x = rng.standard_normal(dim) + 1j * rng.standard_normal(dim)
    x /= np.linalg.norm(x)
    value = 0.0
    for _ in range(NORM_STEPS):
        y = apply(x)
        value_new = float(np.linalg.norm(y))
        z = adjoint(y)
        nz = float(np.linalg.norm(z))
        if nz == 0 or value_new == 0:
            return value_new
        x = z / nz
        if abs(value_new - value) <= 1e-3 * value_new:
            return value_new
        value = value_new
    return value


class Scan:
    """The small-gain bound of the modes a band leaves out, on a frequency scan.

    ``band`` is the :class:`~rheolin.floquet.band.BandAveraged` (balanced right and left
    vectors ``X``, ``W``, eigenvalues ``lam``, scaling ``sq``, ``sv``) of ``system``.
    """

    def __init__(self, system: PeriodicSystem, band: Any) -> None:
        self.system, self.band = system, band
        n = system.n
        self.n, self.w = n, system.omega
        T = touched_dofs(system)
        self.T = T
        self.M0, self.D0, self.K0 = (
            averaged_part(system, t) for t in (system.M, system.D, system.K)
        )
        sq, sv = band.sq[T], band.sv[T]
        self.sq, self.sv = sq, sv
        r = T.size
        self.dense = r <= DENSE_TOUCHED
        # balanced couplings on T: f_b = E_b (q_b, v_b), forces / sv, outputs (sq q, sv v)
        self.E: dict[int, tuple[Any, Any, Any]] = {}
        for k in system.coefficient_harmonics:
            parts: list[Any] = []
            for table, right in ((system.K, sq), (system.D, sv), (system.M, sv)):
                x = table.get(k)
                if x is None:
                    parts.append(None)
                    continue
                block = sp.csr_array(x)[T][:, T]
                block = sp.diags_array(1.0 / sv) @ block @ sp.diags_array(1.0 / right)
                parts.append(block.toarray() if self.dense else sp.csr_array(block))
            self.E[k] = (parts[0], parts[1], parts[2])
        # band part at T: outputs (q, v) of the right vectors, force rows of the left ones
        self.Y = np.concatenate([band.X[T], band.X[n + T]])  # 2r x m (balanced)
        self.Wf = band.W[n + T]  # r x m
        self.rng = np.random.default_rng(31)
        self._lu = PatternLU()  # Q0(i omega) at every point: one pattern
        low = max(float(np.min(np.abs(band.lam), initial=self.w)), 1e-6 * self.w)
        self.low = min(low, self.w) / 10
        # the loop in the energy norm: the band's unbalanced vectors, each harmonic's own
        # touched DOFs and, for a few of them, (S^-1)_TT
        self.Xq = band.X[:n] / band.sq[:, None]  # right vectors, displacements
        self.Wv = band.W[n:] / band.sv[:, None]  # left vectors, force rows
        self.XqH, self.WvH = (np.ascontiguousarray(x.conj().T) for x in (self.Xq, self.Wv))
        radius = float(np.max(np.abs(band.lam), initial=self.w))
        self.sigma = -SPLIT * radius
        # the energy norms of the frequency (energy_norm.EnergyFamily): S at low frequency
        self.family = family = EnergyFamily(self.K0, self.M0, radius)
        self.weight = (family.S, family.solve) if family.definite else None
        self.parts: dict[int, tuple[Any, ...]] = {}
        # harmonics touching few DOFs T_k (gear meshes): their blocks E_k[T_k, T_k] and
        # C_k = J^T S^-1 J, with one set of responses G_C(s) J_U per point on the union U
        self.low_rank: dict[int, tuple[np.ndarray, list[Any], np.ndarray]] = {}
        self.JU = np.zeros((n, 0))  # unit forces on the union U of those T_k
        self.U = np.zeros(0, dtype=np.int64)
        self.WvH_U = np.zeros((band.lam.size, 0), dtype=complex)  # W^H J_U
        if self.weight is None:
            return
        _, solve = self.weight
        for k in system.coefficient_harmonics:
            mats = [table.get(k) for table in (system.K, system.D, system.M)]
            blocks = [None if x is None else sp.csr_array(x) for x in mats]
            self.parts[k] = (nonzero_dofs(blocks), *blocks)
        # harmonics touching many DOFs (a flat shaft): the band's left vectors on their own
        # DOFs only (what the loop's forces and adjoint outputs reach), and the band's part
        # of the block response G E_k X, W^H E_k X = P_K + s P_D + s^2 P_M (band x band)
        self.many: dict[int, tuple[np.ndarray, np.ndarray, list[Any]]] = {}
        for k, (Tk, *blocks) in self.parts.items():
            if Tk.size > LOW_RANK:
                WvH_T = np.ascontiguousarray(self.WvH[:, Tk])
                proj = [None if b is None else WvH_T @ (b @ self.Xq)[Tk] for b in blocks]
                self.many[k] = (WvH_T, np.ascontiguousarray(self.Wv[Tk]), proj)
        few = [Tk for Tk, *_ in self.parts.values() if 0 < Tk.size <= LOW_RANK]
        if not few:
            return
        U = np.unique(np.concatenate(few))
        self.U = U
        self.JU = np.zeros((n, U.size))
        self.JU[U, np.arange(U.size)] = 1.0
        self.WvH_U = np.ascontiguousarray(self.WvH[:, U])
        CU = solve(self.JU)[U]
        for k, (Tk, *blocks) in self.parts.items():
            if 0 < Tk.size <= LOW_RANK:
                at = np.searchsorted(U, Tk)
                small = [None if b is None else b[Tk][:, Tk].toarray() for b in blocks]
                C = CU[np.ix_(at, at)]
                self.low_rank[k] = (at, small, (C + C.conj().T) / 2)

    # ------------------------------------------------------------------ one frequency
    def coupling(self, k: int, s: complex) -> Any:
        """``E_b,k(s) = [K_k, D_k + s M_k]`` on ``(q, v)`` at the touched DOFs, balanced."""
        K, D, M = self.E[k]
        r = self.T.size
        if self.dense:
            Eq = np.zeros((r, r), dtype=complex) if K is None else K
            Ev = np.zeros((r, r), dtype=complex)
            if D is not None:
                Ev = Ev + D
            if M is not None:
                Ev = Ev + s * M
            return np.hstack([Eq, Ev])
        Z = sp.csr_array((r, r))
        Eq = Z if K is None else K
        Ev = (Z if D is None else D) + (Z if M is None else s * M)
        return sp.hstack([Eq, Ev]).tocsr()

    def factor(self, omega: float) -> Any:
        """The sparse LU of ``Q0(i omega)``, or None when it is singular."""
        s = 1j * float(omega)
        Q = sp.csc_array(self.K0 + s * self.D0 + (s * s) * self.M0)
        try:
            return self._lu(Q)
        except RuntimeError:
            return None

    def _energy(self, lu: Any, s: complex) -> tuple[float, float]:
        """``(kappa_C, q_S)`` at ``s = i omega`` in the energy norms of the frequency
        (:class:`~rheolin.floquet.energy_norm.EnergyFamily`): ``sum_k ||G_C(s) E_k(s - i k
        w1)||`` from ``N(omega - k w1)`` to ``N(omega)`` and ``sum_k sum_m ||G_C(s) E_k
        x_m||_N(omega)`` over the band's displacement vectors.

        Each input norm ``N(omega_k)`` is replaced by a smaller one, which can only raise the
        bound: ``N(omega_hi)`` (``omega_hi = max_k |omega - k w1|``, one factor per point)
        or ``alpha(omega_k) S`` (the factor of ``S``), whichever bounds the harmonic's loop
        better (both for the harmonics touching few DOFs; for the others the one whose
        worst case is smaller)."""
        with np.errstate(under="ignore"):  # the scaled norms' tiny entries are zeros
            return self._energy_at(lu, s)

    def _energy_at(self, lu: Any, s: complex) -> tuple[float, float]:
        """:meth:`_energy`, underflow ignored."""
        assert self.weight is not None
        family = self.family
        omega = abs(float(s.imag))
        shifted = {k: abs(omega - k * self.w) for k, (Tk, *_) in self.parts.items() if Tk.size}
        hi = max(shifted.values(), default=omega)
        S = family.output(omega)
        S_hi, solve_hi = family.input(hi)
        fresh = family.varying and hi * hi > SAME_INPUT * family.mu  # N(hi) factorized
        c = self._band_weights(s)
        kappa = qs = 0.0
        CU_hi = None
        if self.low_rank:
            # E_k = J E^_k J^T on T_k within U: ||G_C E_k||^2 is the largest eigenvalue of
            # C_k E^H P E^ with P = (G_C J_U)^H N (G_C J_U) on T_k (C_k = J^T N_in^-1 J: the
            # smallest input energy of a state with given values on T_k); q_S from the same P
            GU = np.asarray(lu.solve(self.JU.astype(complex))) - self.Xq @ (c[:, None] * self.WvH_U)
            PU = GU.conj().T @ apply_norm(S, GU)
            if fresh:
                CU_hi = np.asarray(solve_hi(self.JU))[self.U]
        for k, (Tk, K, D, M) in self.parts.items():
            if Tk.size == 0:
                continue
            sig = s - 1j * k * self.w
            alpha = family.alpha(shifted[k])
            if k in self.low_rank:
                at, (Kh, Dh, Mh), C = self.low_rank[k]
                Eh = _dense_polynomial((Kh, Dh, Mh), sig, Tk.size)
                P = PU[np.ix_(at, at)]
                X = Eh.conj().T @ P @ Eh
                gain = _top(C @ X) / np.sqrt(alpha)  # the input alpha S: S's block scaled
                if CU_hi is not None:  # the input N(hi)
                    Ch = CU_hi[np.ix_(at, at)]
                    gain = min(gain, _top(((Ch + Ch.conj().T) / 2) @ X))
                kappa += gain
                Y = Eh @ self.Xq[Tk]
                energy = np.sum(Y.conj() * (P @ Y), axis=0).real
            else:
                E = _polynomial(K, D, M, sig, self.n)
                apply, adjoint = self._loop(lu, s, k, E)
                # worst cases (squared): alpha S loses 1 / alpha, N(hi) loses
                # N(omega_k) / N(hi) <= alpha / alpha(hi)
                if fresh and alpha / family.alpha(hi) < 1.0 / alpha:
                    S_in, solve = S_hi, solve_hi
                else:
                    S_in, solve = family.scaled(shifted[k])
                kappa += norm_in(apply, adjoint, S, solve, self.n, self.rng, S_in=S_in)
                # G_C E_k X: the band's part from the precomputed projections
                WEX = _dense_polynomial(self.many[k][2], sig, self.Xq.shape[1])
                Z = np.asarray(lu.solve(np.asarray(E @ self.Xq, dtype=complex)))
                Z -= self.Xq @ (c[:, None] * WEX)
                energy = column_energies(S, Z)
            qs += float(np.sum(np.sqrt(np.maximum(energy, 0.0))))
        return kappa, qs

    def _band_weights(self, s: complex) -> np.ndarray:
        """The band's part of ``G(s)`` is ``X diag(c) W^H``: ``c_j = 1/(s - lambda_j) -
        1/(s - sigma)``, its ``1/s`` tail split off (``sigma = -SPLIT * radius``)."""
        return np.asarray(1.0 / (s - self.band.lam) - 1.0 / (s - self.sigma))

    def _loop(self, lu: Any, s: complex, k: int, E: Any) -> tuple[Any, Any]:
        """``x -> G_C(s) E x`` and ``y -> E^H G_C(s)^H y`` for a harmonic ``k`` touching many
        DOFs ``T_k`` (``E`` its coupling at ``s``, ``lu`` the factor of ``Q0(s)``). ``G_C(s)``
        is ``G(s)`` minus the band's ``x_j w_j^H (1/(s - lambda_j) - 1/(s - sigma))``,
        ``sigma = -SPLIT * radius``; ``E x`` lives on ``T_k`` and ``E^H`` reads ``T_k`` only,
        so the band's left vectors enter on ``T_k`` alone."""
        Tk = self.parts[k][0]
        WvH_T, Wv_T, _ = self.many[k]
        c = self._band_weights(s)
        cc = np.conj(c)
        Xq, XqH, n = self.Xq, self.XqH, self.n
        EH = sp.csr_array(E.conj().T)

        def apply(x: np.ndarray) -> np.ndarray:
            F = np.asarray(E @ x, dtype=complex)
            return np.asarray(lu.solve(F)) - Xq @ (c * (WvH_T @ F[Tk]))

        def adjoint(y: np.ndarray) -> np.ndarray:
            y = np.asarray(y, dtype=complex)
            g = np.zeros(n, dtype=complex)
            g[Tk] = np.asarray(lu.solve(y, trans="H"))[Tk] - Wv_T @ (cc * (XqH @ y))
            return np.asarray(EH @ g)

        return apply, adjoint

    def _balanced(self, lu: Any, s: complex, stop: float = float("inf")) -> tuple[float, float]:
        """``(kappa_C, q_S)`` at ``s`` in the Euclidean norm of the balanced first-order state
        at the touched DOFs, with the band's first-order part taken out (``q_S`` infinite,
        not computed, where ``kappa_C`` reaches ``stop``: the norm drops out there)."""
        band = self.band
        c = 1.0 / (s - band.lam)
        T, n, r = self.T, self.n, self.T.size
        sq, sv = self.sq, self.sv
        if self.dense:
            F = np.zeros((n, r), dtype=complex)
            F[T, np.arange(r)] = sv  # balanced unit forces
            G = lu.solve(F)[T]
            H = np.vstack([sq[:, None] * G, sv[:, None] * (s * G)])
            HC = H - (self.Y * c) @ self.Wf.conj().T
            kappa = qs = 0.0
            for k in self.E:
                P = HC @ self.coupling(k, s - 1j * k * self.w)
                kappa += float(np.linalg.norm(P, 2))
                qs += float(np.sum(np.linalg.norm(P @ self.Y, axis=0)))
            return kappa, qs
        return self._operators(lu, s, c, stop)

    def _operators(
        self, lu: Any, s: complex, c: np.ndarray, stop: float = float("inf")
    ) -> tuple[float, float]:
        """:meth:`_balanced` for many touched DOFs: the norms by power iteration."""
        T, n, r = self.T, self.n, self.T.size
        sq, sv, Y, Wf = self.sq, self.sv, self.Y, self.Wf

        def hc(f: np.ndarray) -> np.ndarray:  # one force (r) or a block of them (r x m)
            F = np.zeros((n, *f.shape[1:]), dtype=complex)
            F[T] = (sv * f.T).T
            g = lu.solve(F)[T]
            band_part = Y @ (c * (Wf.conj().T @ f).T).T
            return np.concatenate([(sq * g.T).T, (sv * (s * g).T).T]) - band_part

        def hc_h(y: np.ndarray) -> np.ndarray:
            yq, yv = y[:r], y[r:]
            R = np.zeros(n, dtype=complex)
            R[T] = sq * yq + np.conj(s) * sv * yv
            g = lu.solve(R, trans="H")[T]
            return sv * g - Wf @ (np.conj(c) * (Y.conj().T @ y))

        kappa = qs = 0.0
        couplings = [self.coupling(k, s - 1j * k * self.w) for k in self.E]
        for E in couplings:
            EH = E.conj().T
            kappa += _norm2(
                lambda x, E=E: hc(E @ x), lambda y, EH=EH: EH @ hc_h(y), 2 * r, self.rng
            )
        if not kappa < stop:  # this norm drops out at this point: its q_S is not needed
            return kappa, float("inf")
        for E in couplings:
            qs += float(np.sum(np.linalg.norm(hc(np.asarray(E @ Y)), axis=0)))
        return kappa, qs

    def nearest(self, lu: Any, omega: float, steps: int = 5) -> complex:
        """The time-averaged eigenvalue nearest ``i omega`` (a few shift-invert steps with the
        point's factor; first-order ``y = (q, v)``)."""
        n, M0, D0 = self.n, self.M0, self.D0
        s = 1j * float(omega)
        y = self.rng.standard_normal(2 * n) + 0j
        theta = 0j
        for _ in range(steps):
            q, v = y[:n], y[n:]
            # (A - s B)^-1 B y with A = [[0, I], [-K, -D]], B = diag(I, M)
            x = -lu.solve(M0 @ v + (D0 + s * M0) @ q)
            z = np.concatenate([x, q + s * x])
            nz = np.linalg.norm(z)
            if nz == 0:
                return complex("inf")
            theta = np.vdot(y, z) / np.vdot(y, y)
            y = z / nz
        return complex(s + 1.0 / theta) if theta != 0 else complex("inf")

    # ------------------------------------------------------------------ the scan
    def run(self, top: float, stop: float = float("inf")) -> Complement:
        """The small-gain bound in the energy norm and in the balanced state's norm (the
        energy norm only where ``S`` is definite): each is a complete argument on its own,
        and the one whose largest ``kappa_C`` is smaller is kept (``norm`` in the result).
        Both are evaluated in one scan, sharing each point's factor (:meth:`scan`)."""
        norms = ("energy", "balanced") if self.weight is not None else ("balanced",)
        found = self.scan(top, stop, norms)
        out = min(found.values(), key=lambda c: (not c.complete, c.kappa))
        if np.isfinite(out.beta):  # else the band's radii stay infinite: no coupling needed
            out.p = self._p() if out.norm == "energy" else self._p_balanced()
        # the energy norm's band coordinates carry (lambda_j - sigma) / (s - sigma), at most
        # |lambda_j - sigma| / |sigma| for Re s >= 0: each radius grows by that factor
        out.rho = np.ones(self.band.lam.size)
        if out.norm == "energy":
            out.rho = np.maximum(np.abs(self.band.lam - self.sigma) / abs(self.sigma), 1.0)
        return out

    def scan(self, top: float, stop: float, norms: tuple[str, ...]) -> dict[str, Complement]:
        """The scan from a tenth of the smallest band frequency to ``top`` rad/s (and one
        quasi-static point at a tenth of ``w1`` when that is lower) in each of
        ``norms`` (``"energy"``, ``"balanced"``), refined at the eigenvalue nearest each point
        when its peak may be narrower than the grid.

        The grid is visited coarse to fine (every 16th point first, then those between); a
        norm drops out at the first point where its ``kappa_C >= stop`` (the band is then
        known to fail in it, and its ``kappa`` reports that point's value, a lower bound of
        the largest), and the scan ends when none is left."""
        band = self.band
        measures: dict[str, Callable[[Any, complex], tuple[float, float]]] = {
            "energy": self._energy,
            "balanced": partial(self._balanced, stop=stop),
        }
        # below a tenth of the lowest band frequency the loop is quasi-static: one point at
        # the lowest frequency stands for it (a tenth of the fundamental w1, when lower)
        lowest = float(np.min(np.abs(band.lam), initial=np.inf))
        low = max(lowest if np.isfinite(lowest) else self.w, 1e-6 * self.w) / 10
        grid = scan_grid(low, top, band.radius)
        if self.low < low / 2:
            grid = np.concatenate([[self.low], grid])
        seen: dict[str, list[tuple[float, float, float]]] = {m: [] for m in norms}
        alive = set(norms)
        extra: list[float] = []

        def visit(omega: float) -> Any:
            lu = self.factor(omega)
            for name in norms:
                if name in alive:
                    inf = float("inf")
                    kap, qs = (inf, inf) if lu is None else measures[name](lu, 1j * float(omega))
                    seen[name].append((omega, kap, qs))
                    if not kap < stop:
                        alive.discard(name)
            return lu

        for omega in grid[visiting_order(grid, band.radius)]:
            lu = visit(omega)
            if not alive:
                break
            if lu is None:
                continue
            mu = self.nearest(lu, omega)
            if not np.isfinite(mu) or mu.imag <= 0:
                continue
            near_band = np.min(np.abs(band.lam - mu), initial=np.inf) <= 1e-6 * abs(mu)
            inside = abs(mu) < QUIET * band.radius  # a band mode: no pole of the loop
            if not (near_band or inside) and abs(mu.real) < SPACING * mu.imag:
                extra.append(float(mu.imag))
        else:
            for omega in sorted(set(np.round(extra, 9))):
                visit(omega)
                if not alive:
                    break
        return {name: self._result(name, np.array(seen[name]), name in alive) for name in norms}

    def _result(self, norm: str, arr: np.ndarray, complete: bool) -> Complement:
        """The :class:`Complement` of one norm's scan (rows ``omega, kappa_C, q_S``), without
        the band modes' couplings (:meth:`run` adds them for the norm it keeps)."""
        kappa, qs = arr[:, 1], arr[:, 2]
        i = int(np.argmax(kappa))
        out = Complement(
            certified=False, kappa=float(kappa[i]), at=float(arr[i, 0]), points=len(arr)
        )
        out.norm, out.complete = norm, complete
        if complete and np.all(kappa < 1.0):
            out.beta = float(np.max(qs / (1.0 - kappa)))
        return out

    def _p(self) -> np.ndarray:
        """Each band mode's coupling into the forces, in the dual of the energy norm:
        ``sum_k ||S^-1/2 E_k(s_j)^H w_j||`` with ``s_j = lambda_j - i k w1``."""
        assert self.weight is not None
        solve = self.family.dual_solve()  # the smallest norm of the family: the largest duals
        band, Wv = self.band, self.Wv
        p = np.zeros(band.lam.size)
        for k, (Tk, K, D, M) in self.parts.items():
            if Tk.size == 0:
                continue
            sj = np.conj(band.lam - 1j * k * self.w)
            F = np.zeros_like(Wv)
            if K is not None:
                F += K.conj().T @ Wv
            if D is not None:
                F += (D.conj().T @ Wv) * sj
            if M is not None:
                F += (M.conj().T @ Wv) * sj**2
            Z = solve(F)
            p += np.sqrt(np.maximum(np.sum(F.conj() * Z, axis=0).real, 0.0))
        return p

    def _p_balanced(self) -> np.ndarray:
        """Each band mode's coupling into the touched DOFs' forces: ``||w_j^H J E_k||``
        summed (the balanced state's norm)."""
        band = self.band
        Wf = self.Wf
        p = np.zeros(band.lam.size)
        WfH = Wf.conj().T
        for k, parts in self.E.items():
            # rows j of w_j^H [K_k, D_k + s_j M_k] with s_j = lam_j - i k w1, all j at once
            Kp, Dp, Mp = (None if x is None else np.asarray((x.T @ WfH.T).T) for x in parts)
            sj = (band.lam - 1j * k * self.w)[:, None]
            rows_q = 0.0 if Kp is None else np.abs(Kp) ** 2
            rows_v = (0.0 if Dp is None else Dp) + (0.0 if Mp is None else sj * Mp)
            p += np.sqrt(np.sum(rows_q + np.abs(rows_v) ** 2, axis=1))
        return p


def _top(A: np.ndarray) -> float:
    """The square root of the largest real part of the eigenvalues of ``A`` (a product of
    two Hermitian semidefinite blocks: its eigenvalues are real and nonnegative)."""
    ev = np.linalg.eigvals(A)
    return float(np.sqrt(max(float(np.max(ev.real, initial=0.0)), 0.0)))


def _dense_polynomial(parts: Any, sig: complex, size: int) -> np.ndarray:
    """``K + sig D + sig^2 M`` of dense ``parts = (K, D, M)`` (absent ones are zero)."""
    out = np.zeros((size, size), dtype=complex)
    for part, factor in zip(parts, (1.0, sig, sig * sig), strict=True):
        if part is not None:
            out += factor * part
    return out


def _polynomial(K: Any, D: Any, M: Any, sig: complex, n: int) -> sp.csc_array:
    """``K + sig D + sig^2 M`` (absent parts are zero), sparse."""
    out = sp.csc_array((n, n), dtype=complex)
    if K is not None:
        out = out + K
    if D is not None:
        out = out + sig * D
    if M is not None:
        out = out + (sig * sig) * M
    return sp.csc_array(out)
