"""Time-domain evaluation of a periodic system for the transient baseline: coefficients
at time t, the inverse of a time-varying mass, and the periodic steady-state detector."""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...system.periodic import PeriodicSystem
from .settings import DENSE_MAX, STALL_NOISE, STALL_RATIO, STALL_WINDOW, WOODBURY_MAX

if TYPE_CHECKING:
    from ...harmonics.balance import HarmonicBalance
    from .settings import TransientSettings

__all__ = ["Coefficients", "Detector", "MassInverse", "Series", "SingularMass"]

log = logging.getLogger(__name__)


class Series:
    """``X(t) = X_0 + dX(t)`` of one of M, D, K.

    ``const`` is ``X_0`` (dense for small systems, else CSR; or None). The time-varying part
    lives on its support: rows ``R``, columns ``C`` and a dense ``|R| x |C|`` block ``sub``
    whose entries ``(ri, ci)`` are refreshed from ``table`` (rows: cos, then sin, per basis
    harmonic), as the operator does for ``dA`` (a gear mesh touches two nodes).
    """

    def __init__(self, coeffs: dict[int, Any], n: int, ks: np.ndarray, dense: bool) -> None:
        self.n = n
        x0 = coeffs.get(0)
        if x0 is None:
            self.const: Any = None
        else:
            self.const = (
                (x0.toarray() if sp.issparse(x0) else np.asarray(x0, dtype=float))
                if dense
                else sp.csr_array(x0, dtype=float)
            )
        var = {k: sp.coo_array(sp.csr_array(x)) for k, x in coeffs.items() if k > 0}
        keys = np.unique(
            np.concatenate(
                [np.zeros(0, dtype=np.int64)]
                + [x.row.astype(np.int64) * n + x.col for x in var.values()]
            )
        )
        self.rows, self.cols = keys // n, keys % n  # global (row, col) of each entry
        self.R, self.C = np.unique(self.rows), np.unique(self.cols)
        self.ri, self.ci = np.searchsorted(self.R, self.rows), np.searchsorted(self.C, self.cols)
        self.sub = np.zeros((self.R.size, self.C.size))
        self.table = np.zeros((2 * ks.size, keys.size))
        where = {int(k): i for i, k in enumerate(ks)}
        for k, x in var.items():
            c = np.zeros(keys.size, dtype=complex)
            np.add.at(c, np.searchsorted(keys, x.row.astype(np.int64) * n + x.col), x.data)
            self.table[where[k]] = 2 * c.real
            self.table[ks.size + where[k]] = -2 * c.imag

    @property
    def varies(self) -> bool:
        """True when the coefficient has a time-varying part."""
        return bool(self.rows.size)

    def refresh(self, basis: np.ndarray) -> np.ndarray:
        """Refresh ``sub`` at the basis ``(cos k w t, sin k w t)``; return the entries."""
        data = basis @ self.table
        self.sub[self.ri, self.ci] = data
        return data

    def matvec(self, x: np.ndarray) -> np.ndarray:
        """``X(t) x`` (as last refreshed)."""
        out = self.const @ x if self.const is not None else np.zeros(self.n)
        if self.varies:
            out[self.R] += self.sub @ x[self.C]
        return out

    def matrix(self) -> Any:
        """``X(t)`` (as last refreshed): dense or CSR like ``const``."""
        var = sp.csr_array((self.sub[self.ri, self.ci], (self.rows, self.cols)), (self.n,) * 2)
        if isinstance(self.const, np.ndarray):
            return self.const + var.toarray()
        return var if self.const is None else sp.csr_array(self.const + var)


class Coefficients:
    """``M(t)``, ``D(t)``, ``K(t)``, ``f(t)`` of a periodic system, evaluated fast."""

    def __init__(self, system: PeriodicSystem) -> None:
        self.n = n = system.n
        self.w = system.omega
        self.dense = n <= DENSE_MAX
        ks = sorted({k for c in (system.M, system.D, system.K, system.f) for k in c if k > 0})
        self.ks = np.array(ks, dtype=float)
        self.M = Series(system.M, n, self.ks, self.dense)
        self.D = Series(system.D, n, self.ks, self.dense)
        self.K = Series(system.K, n, self.ks, self.dense)
        self.f0 = system.f[0].astype(float) if 0 in system.f else np.zeros(n)
        self.f_table = np.zeros((2 * len(ks), n))
        for i, k in enumerate(ks):
            if k in system.f:
                self.f_table[i] = 2 * system.f[k].real
                self.f_table[len(ks) + i] = -2 * system.f[k].imag
        if self.M.const is None:
            raise ValueError("the transient method needs a mean mass matrix M_0; M has none")

    def basis(self, t: float) -> np.ndarray:
        """``(cos k w t ..., sin k w t ...)`` over the positive harmonics present."""
        ph = self.ks * (self.w * t)
        return np.concatenate([np.cos(ph), np.sin(ph)])

    def refresh(self, t: float) -> np.ndarray:
        """Refresh M, D, K at ``t``; return ``f(t)``."""
        b = self.basis(t)
        for s in (self.M, self.D, self.K):
            if s.varies:
                s.refresh(b)
        return self.f0 + b @ self.f_table

    def mass_inverse(self) -> MassInverse:
        """``M(t)^-1`` at the time of the last refresh (raises :class:`SingularMass`)."""
        return MassInverse(self.M)


class MassInverse:
    """``M(t)^-1 x`` from one factorization of ``M_0`` and the Woodbury identity on the
    support of ``dM`` (``M = M_0 + P_R S P_C^T``), or an LU of ``M(t)`` per call when that
    support is large."""

    def __init__(self, series: Series) -> None:
        self.series = m = series
        M0 = m.const
        try:
            if isinstance(M0, np.ndarray):
                self.inv0: Any = np.linalg.inv(M0)
                self.solve0: Callable[[np.ndarray], np.ndarray] = self.inv0.__matmul__
            else:
                self.solve0 = spla.splu(sp.csc_array(M0)).solve
        except (RuntimeError, np.linalg.LinAlgError) as exc:
            raise SingularMass(str(exc)) from None
        self.woodbury = m.varies and max(m.R.size, m.C.size) <= WOODBURY_MAX
        if self.woodbury:
            P = np.zeros((m.n, m.R.size))
            P[m.R, np.arange(m.R.size)] = 1.0
            self.W = self.solve0(P)  # M_0^-1 P_R
            self.G = self.W[m.C]  # P_C^T M_0^-1 P_R
            self.eye = np.eye(m.R.size)

    def solve(self, x: np.ndarray) -> np.ndarray:
        """``M(t)^-1 x`` (``x`` of shape (n,) or (n, k)), ``M`` as last refreshed."""
        m = self.series
        if not m.varies:
            return self.solve0(x)
        if not self.woodbury:
            try:
                Mt = m.matrix()
                if isinstance(Mt, np.ndarray):
                    return np.linalg.solve(Mt, x)
                return spla.splu(sp.csc_array(Mt)).solve(x)
            except (RuntimeError, np.linalg.LinAlgError) as exc:
                raise SingularMass(str(exc)) from None
        # (M0 + P_R S P_C^T)^-1 = M0^-1 - W (I + S G)^-1 S P_C^T M0^-1
        y = self.solve0(x)
        small = np.linalg.solve(self.eye + m.sub @ self.G, m.sub @ y[m.C])
        return y - self.W @ small


class SingularMass(RuntimeError):
    """``M`` could not be factorized."""


# --------------------------------------------------------------------------- detector
class Detector:
    """Collects samples period by period and decides when the response is periodic."""

    def __init__(self, s: TransientSettings, n: int, callback: Callable | None) -> None:
        self.s = s
        self.dt = s.period / s.samples
        self.prev = np.zeros((s.samples, n))
        self.cur = np.zeros((s.samples, n))
        self.index = 0  # global sample counter
        self.periods = 0  # completed periods
        self.history: list[float] = []
        self.callback = callback
        self.done = False  # stop integrating (converged or stalled)
        self.stalled = False  # stopped because the change sits at the integrator's noise

    def next_time(self) -> float:
        return self.index * self.dt

    def pending(self, t: float) -> np.ndarray:
        """Sample times ``<= t`` not yet taken (at most to the end of the current period)."""
        last = min(math.floor(t / self.dt * (1 + 1e-15)), (self.periods + 1) * self.s.samples - 1)
        if last < self.index:
            return np.zeros(0)
        return np.arange(self.index, last + 1) * self.dt

    def take(self, q: np.ndarray) -> None:
        """Store samples (rows of ``q``) and close the period when it is complete."""
        j = self.index - self.periods * self.s.samples
        self.cur[j : j + q.shape[0]] = q
        self.index += q.shape[0]
        if self.index == (self.periods + 1) * self.s.samples:
            self.periods += 1
            if self.periods >= 2:
                scale = float(np.max(np.abs(self.cur)))
                change = float(np.max(np.abs(self.cur - self.prev))) / scale if scale else 0.0
                self.history.append(change)
                if self.callback is not None:
                    self.callback(self.periods, change)
                self.done = change <= self.s.period_tol
                if not self.done and self._stalled():
                    self.done = self.stalled = True
            if not self.done:
                self.prev, self.cur = self.cur, self.prev

    def _stalled(self) -> bool:
        h = self.history
        if len(h) <= STALL_WINDOW or h[-1] > STALL_NOISE * self.s.rtol:
            return False
        old = h[-1 - STALL_WINDOW]
        return old > 0 and (h[-1] / old) ** (1 / STALL_WINDOW) > STALL_RATIO

    def harmonics(self, op: HarmonicBalance) -> np.ndarray:
        """Coefficients ``q_n``, ``n >= 0``, from the DFT of the last complete period."""
        F = np.fft.fft(self.cur, axis=0) / self.s.samples
        Q = np.zeros((op.pos.size, op.n_dof), dtype=complex)
        for i, n in enumerate(op.pos):
            m = n / self.s.divisor
            if abs(m - round(m)) < 1e-9:
                Q[i] = F[round(m) % self.s.samples]
        return Q
