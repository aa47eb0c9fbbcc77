"""What a band of time-averaged modes leaves out, bounded (docs/stability.md, section 8).

Two certificates make the band search (:mod:`rheolin.floquet.band`) complete:

* the **energy bound**: every time-averaged eigenvalue with ``|lambda|`` above a radius ``r``
  has ``Re <= 0`` when ``K_s + r^2 M`` and ``D_s - i N / r`` are positive definite (``K_s``,
  ``N`` the symmetric and skew parts of ``K_0``, ``D_s`` that of ``D_0``): two sparse
  factorizations (:func:`energy_certificate`);
* the **small-gain bound**: no exponent with ``Re >= 0`` comes from the modes outside the band
  when ``kappa_C(s) = sum_k ||G_C(s) E_k(s - i k w1)|| < 1`` on the imaginary axis, ``G_C``
  the time-averaged transfer function minus its band part, in a fixed norm: the energy norm
  (:mod:`rheolin.floquet.energy_norm`) or the Euclidean norm of the balanced state at the
  DOFs the time variation touches, whichever bounds it better; a frequency scan
  (:class:`~rheolin.floquet.scan.Scan`). It also gives ``beta*``, by which each band mode's
  Gershgorin radius grows (the coupling through the modes left out).

>>> import numpy as np, rheolin as rl
>>> s = rl.PeriodicSystem(1.0, M={0: np.eye(2)}, D={0: 0.1 * np.eye(2)},
...                       K={0: np.diag([4.0, 9.0])})
>>> energy_certificate(s, 0.0)[0], round(energy_radius(s), 6)
(True, 0.0)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..system.periodic import PeriodicSystem
from .energy_norm import positive_definite

__all__ = [
    "KAPPA_LIMIT",
    "Complement",
    "averaged_part",
    "energy_certificate",
    "energy_radius",
    "harmonic_dofs",
    "nonzero_dofs",
    "touched_dofs",
]

#: The small-gain bound must stay below this (1 is the limit of the argument; the margin
#: keeps ``beta*``, and with it the band's Gershgorin radii, moderate).
KAPPA_LIMIT = 0.5


@dataclass
class Complement:
    """The certificates of the modes left out by a band (:class:`~rheolin.floquet.scan.Scan`).

    ``certified``: the small-gain bound holds (else ``reason`` says what failed and what to
    change); ``energy``: the energy bound holds too (``energy_note`` says why not);
    ``kappa`` the scan's largest ``kappa_C`` (at ``at`` rad/s), ``beta`` the radius factor,
    ``p`` per band mode its coupling into the modes left out and ``rho`` the factor of its
    radius (``R_j = rho_j (R_j + beta p_j)``), ``norm`` the norm the loop was measured in
    (``"energy"`` or ``"balanced"``), ``radius`` the energy bound's radius tested,
    ``points`` the frequencies scanned.
    """

    certified: bool
    reason: str = ""
    energy: bool = False
    energy_note: str = ""
    kappa: float = float("inf")
    at: float = float("nan")
    beta: float = float("inf")
    radius: float = float("nan")
    points: int = 0
    complete: bool = True
    p: np.ndarray = field(default_factory=lambda: np.zeros(0))
    rho: np.ndarray = field(default_factory=lambda: np.zeros(0))
    norm: str = "balanced"

    def summary(self) -> dict[str, Any]:
        return {
            "certified": self.certified,
            "reason": self.reason,
            "energy_bound": self.energy,
            "energy_note": self.energy_note,
            "kappa": self.kappa,
            "kappa_at": self.at,
            "beta": self.beta,
            "energy_radius": self.radius,
            "scan_points": self.points,
            "norm": self.norm,
        }


def touched_dofs(system: PeriodicSystem) -> np.ndarray:
    """The DOFs the time variation touches: rows and columns of every ``K_k, D_k, M_k``,
    ``k != 0``."""
    return nonzero_dofs(
        x for table in (system.K, system.D, system.M) for k, x in table.items() if k != 0
    )


def harmonic_dofs(system: PeriodicSystem) -> list[int]:
    """How many DOFs each coefficient harmonic ``k != 0`` touches (rows and columns of its
    ``K_k, D_k, M_k``)."""
    return [
        nonzero_dofs(table.get(k) for table in (system.K, system.D, system.M)).size
        for k in system.coefficient_harmonics
    ]


def nonzero_dofs(matrices: Any) -> np.ndarray:
    """The rows and columns of the nonzero entries of ``matrices`` (None entries skipped)."""
    out: list[np.ndarray] = [np.zeros(0, dtype=np.int64)]
    for x in matrices:
        if x is None:
            continue
        coo = sp.coo_array(x)
        nz = coo.data != 0
        out += [coo.row[nz].astype(np.int64), coo.col[nz].astype(np.int64)]
    return np.unique(np.concatenate(out))


def averaged_part(system: PeriodicSystem, table: dict) -> sp.csc_array:
    """The time-averaged (harmonic 0) matrix of ``table`` (``system.K``, ``D`` or ``M``),
    sparse; zero when absent."""
    x = table.get(0)
    return sp.csc_array((system.n, system.n)) if x is None else sp.csc_array(x)


def energy_certificate(system: PeriodicSystem, radius: float) -> tuple[bool, str]:
    """Whether every time-averaged eigenvalue with ``|lambda| > radius`` has ``Re <= 0``:
    ``K_s + radius^2 M`` positive definite and ``D_s - i N / radius`` positive semidefinite
    (tested with a shift of ``1e-9`` of the damping's diagonal scale). Returns
    ``(ok, reason)``."""
    M, D, K = (averaged_part(system, t) for t in (system.M, system.D, system.K))
    Ks, N = (K + K.T) / 2, (K - K.T) / 2
    Ds = (D + D.T) / 2
    ok_k = positive_definite(Ks + radius * radius * M)
    if not ok_k:
        return False, (
            f"K_s + r^2 M is not positive definite at r = {radius:.4g} rad/s: the "
            "time-averaged stiffness softens faster than the band reaches"
        )
    # semidefinite, tested as definite after a shift of 1e-9 of the damping's largest
    # diagonal entry (the bound then holds to a real part of that order)
    eps = 1e-9 * max(float(np.abs(Ds.diagonal()).max(initial=0.0)), 1e-300)
    skew = abs(N).max() if N.nnz else 0.0
    if skew == 0.0:
        ok_d = positive_definite(Ds + eps * sp.identity(system.n, format="csc"))
    else:
        if radius <= 0:
            return False, "circulatory stiffness terms and no band to bound them"
        shifted = Ds.astype(complex) - 1j * N / radius + eps * sp.identity(system.n, format="csc")
        ok_d = positive_definite(shifted)
    if not ok_d:
        return False, (
            f"D_s - i N / r is not positive semidefinite at r = {radius:.4g} rad/s: "
            "circulatory terms without damping to match them (or negative damping)"
        )
    return True, ""


def energy_radius(system: PeriodicSystem, top: float = 1e12) -> float:
    """The smallest radius (to 1 %) at which :func:`energy_certificate` holds (``inf`` when
    it does not hold up to ``top``)."""
    if energy_certificate(system, 0.0)[0]:
        return 0.0
    lo, hi = 0.0, 1.0
    while not energy_certificate(system, hi)[0]:
        lo, hi = hi, hi * 4
        if hi > top:
            return float("inf")
    while hi > 1.01 * max(lo, 1e-300) and hi - lo > 1e-12:
        mid = np.sqrt(lo * hi) if lo > 0 else hi / 4
        if energy_certificate(system, mid)[0]:
            hi = mid
        else:
            lo = mid
        if lo == 0 and hi < 1e-12:
            break
    return float(hi)
