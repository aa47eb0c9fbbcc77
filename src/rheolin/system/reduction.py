"""Craig-Bampton reduction of a large periodic system for its stability map.

The DOFs a local time variation acts on (a gear mesh's nodes: the *boundary*) are kept;
the rest (the shafts' interior, the housing) is written in its static constraint modes and
the fixed-interface modes below a cut-off frequency:

    q = T p,   T = [[I, 0], [Psi, Phi]],   Psi = -K_ii^-1 K_ib,
    K_ii Phi = M_ii Phi Omega^2,   Phi^T M_ii Phi = I,

with ``K``, ``M`` the symmetric real parts of the time-averaged ``K_0``, ``M_0``. Every
coefficient of the system is projected, ``X_k -> T^T X_k T`` (a time variation on interior
DOFs, the stiffness of a shaft with a flat, acts on its modes), so the reduced Hill operator
on a lattice is the Galerkin projection of the full one on the same harmonics: its
exponents are those of the full system where the left-out modes (fixed-interface modes
above the cut-off) do not take part. The Floquet verdict on the reduced system estimates
what they would change (:mod:`rheolin.floquet.reduced`); docs/stability.md, section 9.

The basis depends on the interior's ``K`` and ``M`` only, so a map's speeds share it
(:meth:`Reduction.project`), and each speed's estimate says how well it still fits.

>>> import numpy as np, scipy.sparse as sp, rheolin as rl
>>> n = 40  # a fixed-free chain of springs and masses, its first spring varying in time
>>> K = sp.diags_array([np.r_[2.0 * np.ones(n - 1), 1.0], -np.ones(n - 1), -np.ones(n - 1)],
...                    offsets=[0, 1, -1]).tocsc() * 1e4
>>> k1 = sp.csc_array(([500.0], ([0], [0])), shape=(n, n))
>>> s = rl.PeriodicSystem(3.0, M={0: sp.eye_array(n, format="csc")},
...                       D={0: 1e-4 * K}, K={0: K, 1: k1})
>>> red = craig_bampton(s, cutoff=60.0)
>>> red.boundary.tolist(), red.modes, red.system.n
([0], 8, 9)
>>> bool(np.all(red.frequencies <= 60.0)), bool(red.next_frequency > 60.0)
(True, True)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import ModelError
from .periodic import PeriodicSystem

__all__ = [
    "CLEAN",
    "LOCAL_SUPPORT",
    "Reduction",
    "craig_bampton",
    "local_boundary",
]

#: A time-varying coefficient acting on at most this many DOFs is local (a mesh, a bearing):
#: its DOFs are kept. One acting on more (a shaft with a flat: every DOF of the shaft) is
#: projected on the interior modes.
LOCAL_SUPPORT = 200

#: Entries of a basis vector below this fraction of its largest are round-off (an
#: eigensolver's vector is never exactly zero on a body it does not move), and so are
#: entries of a projected coefficient below this fraction of its largest: both are set to
#: zero, which keeps the reduced coefficients sparse (on the finely meshed gearbox 635 of
#: the 5,209 entries of the reduced ``K_0`` are above it).
CLEAN = 1e-12


def _csc(x: Any) -> sp.csc_array:
    return sp.csc_array(x) if sp.issparse(x) else sp.csc_array(np.asarray(x))


def local_boundary(system: PeriodicSystem) -> np.ndarray:
    """The DOFs of the time-varying coefficients that act on at most :data:`LOCAL_SUPPORT`
    DOFs (sorted).

    >>> import numpy as np, rheolin as rl
    >>> s = rl.PeriodicSystem(1.0, M={0: np.eye(3)}, K={0: np.eye(3), 2: np.diag([0, 0.1, 0])})
    >>> local_boundary(s).tolist()
    [1]
    """
    dofs: list[np.ndarray] = [np.zeros(0, dtype=np.int64)]
    for table in (system.M, system.D, system.K):
        for k, x in table.items():
            if k == 0:
                continue
            coo = _csc(x).tocoo()
            keep = coo.data != 0
            support = np.union1d(coo.row[keep], coo.col[keep])
            if 0 < support.size <= LOCAL_SUPPORT:
                dofs.append(support.astype(np.int64))
    return np.unique(np.concatenate(dofs))


@dataclass
class Reduction:
    """A Craig-Bampton basis ``T`` (``n x (boundary + modes)``) and the reduced system.

    ``frequencies``: the kept fixed-interface modes [rad/s]; ``next_frequency``: the lowest
    one left out (a lower bound of it: the next eigenvalue the eigensolver found);
    ``interior_lu``: the factor of ``K_ii`` the reduction estimate solves with.
    """

    system: PeriodicSystem
    T: np.ndarray
    boundary: np.ndarray
    interior: np.ndarray
    frequencies: np.ndarray
    next_frequency: float
    cutoff: float
    interior_lu: Any = field(repr=False, default=None)
    seconds: float = 0.0
    #: what the reduction estimate derives from the interior coefficients, by their contents
    #: (a map's speeds share those that do not change with the speed)
    cache: dict[Any, Any] = field(repr=False, default_factory=dict)

    @property
    def modes(self) -> int:
        return int(self.frequencies.size)

    def project(self, system: PeriodicSystem) -> PeriodicSystem:
        """``system`` (the same DOFs, another speed) in this basis."""
        return _projected(system, self.T)

    def lift(self, p: np.ndarray) -> np.ndarray:
        """Full DOF vectors ``T p`` of reduced ones (columns)."""
        return self.T @ p


def craig_bampton(
    system: PeriodicSystem,
    cutoff: float,
    boundary: np.ndarray | None = None,
    *,
    max_modes: int = 2000,
) -> Reduction:
    """The Craig-Bampton reduction of ``system`` (module docstring) with the fixed-interface
    modes up to ``cutoff`` [rad/s]; ``boundary``: the DOFs kept (default
    :func:`local_boundary`). Refuses (:class:`~rheolin.errors.ModelError`) a system with
    exact constraints, or one whose interior needs more than ``max_modes`` modes below the
    cut-off."""
    import time

    t0 = time.perf_counter()
    if system.constraint is not None:
        raise ModelError(
            "craig_bampton: the system has exact constraints (rigid links); reduce it with "
            "its constraint first (LinearConstraint.reduce)"
        )
    if not (np.isfinite(cutoff) and cutoff > 0):
        raise ModelError(f"craig_bampton: `cutoff` must be a frequency > 0 in rad/s, got {cutoff}")
    n = system.n
    b = local_boundary(system) if boundary is None else np.unique(np.asarray(boundary, int))
    if b.size and (b.min() < 0 or b.max() >= n):
        raise ModelError(f"craig_bampton: `boundary` must hold DOF indices 0..{n - 1}")
    i = np.setdiff1d(np.arange(n), b)
    if i.size == 0:
        raise ModelError("craig_bampton: nothing to reduce (every DOF is on the boundary)")
    K = _csc(system.K.get(0, sp.csc_array((n, n))))
    M = _csc(system.M.get(0, sp.csc_array((n, n))))
    Ks = sp.csc_array(((K + K.T) * 0.5).real)
    Ms = sp.csc_array(((M + M.T) * 0.5).real)
    Kii, Kib = sp.csc_array(Ks[i][:, i]), sp.csc_array(Ks[i][:, b])
    Mii = sp.csc_array(Ms[i][:, i])
    try:
        lu = spla.splu(Kii)
    except RuntimeError:
        raise ModelError(
            "craig_bampton: the interior stiffness is singular (a body with no boundary DOF "
            "and no support); add its DOFs to `boundary`"
        ) from None
    psi = -lu.solve(Kib.toarray()) if b.size else np.zeros((i.size, 0))
    freqs, phi, nxt = _interior_modes(Kii, Mii, cutoff, max_modes)
    T = np.zeros((n, b.size + freqs.size))
    T[b, np.arange(b.size)] = 1.0
    T[np.ix_(i, np.arange(b.size))] = psi
    T[np.ix_(i, b.size + np.arange(freqs.size))] = phi
    # the eigensolver's round-off spreads every mode thinly over every body: cleared, so that
    # a body's coefficients stay a block of its own modes in the reduced system
    scale = np.abs(T).max(axis=0, initial=0.0)
    T[np.abs(T) <= CLEAN * scale[None, :]] = 0.0
    return Reduction(
        _projected(system, T), T, b, i, freqs, nxt, float(cutoff), lu, time.perf_counter() - t0
    )


def _interior_modes(
    Kii: sp.csc_array, Mii: sp.csc_array, cutoff: float, max_modes: int
) -> tuple[np.ndarray, np.ndarray, float]:
    """Fixed-interface modes below ``cutoff`` (M-orthonormal) and the next frequency."""
    m = Kii.shape[0]
    if m <= 400:  # small: every mode densely
        import scipy.linalg as sla

        w2, V = sla.eigh(Kii.toarray(), Mii.toarray())
        w = np.sqrt(np.maximum(w2, 0.0))
        keep = w <= cutoff
        nxt = float(w[~keep].min()) if np.any(~keep) else float("inf")
        return w[keep], V[:, keep], nxt
    k = min(32, m - 2)
    while True:
        w2, V = spla.eigsh(Kii, k=k, M=Mii, sigma=0.0, which="LM")
        order = np.argsort(w2)
        w2, V = w2[order], V[:, order]
        w = np.sqrt(np.maximum(w2, 0.0))
        if w[-1] > cutoff or k >= m - 2:
            keep = w <= cutoff
            nxt = float(w[~keep].min()) if np.any(~keep) else float("inf")
            return w[keep], V[:, keep], nxt
        if k >= max_modes:
            raise ModelError(
                f"craig_bampton: more than {max_modes} interior modes lie below the cut-off of "
                f"{cutoff:.4g} rad/s; lower the cut-off or raise `max_modes`"
            )
        k = min(2 * k, m - 2, max_modes + 1)


def _projected(system: PeriodicSystem, T: np.ndarray) -> PeriodicSystem:
    """``system`` with every coefficient ``T^T X_k T`` (kept sparse where it is zero)."""

    def project(x: Any) -> sp.csc_array:
        X = _csc(x)
        coo = X.tocoo()
        rows, cols = np.unique(coo.row), np.unique(coo.col)
        if rows.size == 0:
            return sp.csc_array((T.shape[1], T.shape[1]), dtype=X.dtype)
        # only the rows of T the coefficient touches: a mesh's few DOFs stay a small block
        sub = X[rows][:, cols]
        P = T[rows].T @ (sub @ T[cols])
        P[np.abs(P) <= 0.01 * CLEAN * np.abs(P).max(initial=0.0)] = 0.0
        return sp.csc_array(P)

    out = PeriodicSystem(
        system.omega,
        M={k: project(x) for k, x in system.M.items()},
        D={k: project(x) for k, x in system.D.items()},
        K={k: project(x) for k, x in system.K.items()},
    )
    return out
