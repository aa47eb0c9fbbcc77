"""Rigid-body modes of a periodic system: found, and constrained.

A model with a free axial or torsional motion (a ROSS-style rotor on radial bearings only, a
gear train without a drive stiffness) has a mean stiffness ``K_0`` with a null space that
carries mass: its rigid-body modes ``R`` (``K_0 R = 0``, ``R^T M_0 R = I``). At harmonic 0
the time-averaged block ``A0(0) = K_0`` is then singular, and Floquet analysis sees a double
exponent at zero (a Jordan block) that round-off splits into a false pair ``+-sqrt(eps)``.

A steady operating point at a given speed presumes that something holds these motions: the
drive holds the speed, a thrust bearing the axial position. :func:`find_rigid_modes` finds
the modes and :class:`RigidModes` imposes that: ``R^T M_0 q(t) = 0`` at every instant (the
constant-speed assumption of rotordynamics), by eliminating one DOF per mode,
``q = T y``, and projecting the equations with ``T^T`` (the constraint force ``M_0 R lambda``
drops out because ``T^T M_0 R = 0``). The elastic modes of the free system are ``M_0``-
orthogonal to ``R``, so they are kept exactly. The mean load on a rigid mode, ``R^T f_0``,
is what the constraint takes (the drive torque, the thrust): it is reported.

>>> import numpy as np
>>> M = np.diag([1.0, 1.0]); K = np.array([[1.0, -1.0], [-1.0, 1.0]])  # two masses, one spring
>>> s = PeriodicSystem(1.0, M={0: M}, K={0: K}, f={1: np.array([1.0, 0.0])})
>>> rigid = find_rigid_modes(s)
>>> rigid.count, np.round(rigid.modes.ravel() * np.sqrt(2), 12).tolist()
(1, [1.0, 1.0])
>>> r = rigid.reduce(s); r.n, r.coefficient("K", 0).tolist()  # the elastic mode: k_eff = 2 k
(1, [[4.0]])
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import ModelError
from .constraints import LinearConstraint
from .motions import FreeMotion
from .periodic import PeriodicSystem

__all__ = [
    "DENSE_LIMIT",
    "RIGID_TOL",
    "FreeBodyError",
    "RigidModes",
    "find_rigid_modes",
    "free_body_message",
    "held_rigid_modes",
    "unheld_motions",
]

#: A vector ``v`` is a rigid-body mode when ``||K v|| <= RIGID_TOL || |K| |v| ||`` (mass-scaled
#: ``K``): its stiffness forces cancel to round-off (~1e-15 once refined), while a body on a
#: soft support keeps the support's force (a 1e3 N/m spring under a 1e9 N/m body: ~1e-6).
#: A local test: next to a 1e12 N/m support, eigenvalues carry an absolute error of
#: ``eps x 1e12`` and cannot tell a soft spring from none.
RIGID_TOL = 1e-11
#: Eigenvalues up to this fraction of the largest are candidates (eigh's absolute accuracy).
_CANDIDATE = 1e-8
#: Up to this size the search is one dense symmetric eigendecomposition; above, shift-invert
#: Lanczos near zero.
DENSE_LIMIT = 1000
#: Lanczos: how many eigenvalues nearest zero are looked at (more rigid modes than this are
#: refused with a message).
_SPARSE_K = 12


_TOO_MANY = (
    "bearings: the model has at least {count} rigid-body modes (free motions with mass): "
    "support the bodies (bearings with axial and torsional components, a drive stiffness) "
    "so that each has at most a few free motions"
)


def _dense(x: Any) -> np.ndarray:
    return x.toarray() if sp.issparse(x) else np.asarray(x)


def _diagonal(x: Any) -> np.ndarray:
    return np.asarray(x.diagonal() if sp.issparse(x) else np.diag(np.asarray(x)), dtype=float)


@dataclass
class RigidModes(LinearConstraint):
    """Rigid-body modes ``R`` (``n x k``, ``R^T M_0 R = I``) and the constraint that holds them.

    ``pivots`` are the eliminated DOFs (one per mode, where no time-varying coefficient acts
    when possible), ``keep`` the others; ``q[keep] = y`` and ``q[pivots] = G y``
    (:class:`~rheolin.system.constraints.LinearConstraint`).
    """

    modes: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))

    @property
    def count(self) -> int:
        return int(self.modes.shape[1])

    def mean_load(self, system: PeriodicSystem) -> np.ndarray:
        """``R^T f_0`` per mode: the mean load the constraint takes (the drive, the thrust)."""
        return self.modes.T @ np.real(system.load(0))

    def dominant_dofs(self, system: PeriodicSystem) -> list[int]:
        """Per mode, the DOF with the largest mass-weighted amplitude (to name the motion)."""
        m = np.abs(_diagonal(system.coefficient("M", 0)))
        return [int(np.argmax(np.abs(r) * np.sqrt(m))) for r in self.modes.T]

    def note(self, system: PeriodicSystem) -> str:
        """One sentence for ``Solution.message`` / ``FloquetResult.info['note']``."""
        load = self.mean_load(system)
        k = self.count
        text = (
            f"{k} rigid-body mode{'s' if k > 1 else ''} (free motion with mass: K_0 is singular) "
            f"constrained: R^T M_0 q = 0 at every instant (the drive holds the speed, a thrust "
            "bearing the axial position; docs/solvers.md)"
        )
        if np.abs(load).max(initial=0.0) > 0.0:
            motions = getattr(system, "motions", None)
            named = []
            if motions is not None:
                for r, work in zip(self.modes.T, load, strict=True):
                    body, what, value, unit = motions.held_load(motions.full(r), work)
                    if body and value:
                        named.append(f"{value:.4g} {unit} on the {what} of {body!r}")
            text += f"; the constraint takes the mean load on {'them' if k > 1 else 'it'}, " + (
                ", ".join(named)
                if named
                else f"R^T f_0 = {', '.join(f'{x:.3g}' for x in load)} (mass-normalized modes)"
            )
        return text


def _varying_dofs(system: PeriodicSystem) -> np.ndarray:
    """DOFs a time-varying coefficient touches (rows or columns)."""
    touched = np.zeros(system.n, bool)
    for name in ("M", "D", "K"):
        for k, X in getattr(system, name).items():
            if k == 0:
                continue
            c = sp.coo_array(X) if sp.issparse(X) else sp.coo_array(np.asarray(X))
            touched[c.row] = True
            touched[c.col] = True
    return touched


def _candidates(Ks: Any, n: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Eigenpairs of the symmetric part of the mass-scaled stiffness nearest zero, and its
    largest eigenvalue magnitude."""
    if n <= DENSE_LIMIT:
        A = _dense(Ks)
        lam, V = np.linalg.eigh(0.5 * (A + A.T))
        return lam, V, float(np.abs(lam).max(initial=0.0))
    S = sp.csc_array(0.5 * (Ks + Ks.T))
    scale = float(abs(S).sum(axis=1).max())  # Gershgorin bound of the largest eigenvalue
    if scale == 0.0:
        return np.zeros(0), np.zeros((n, 0)), 0.0
    shift = -1e-8 * scale  # nonsingular, and nearest to the rigid modes
    lam, V = spla.eigsh(S, k=min(_SPARSE_K, n - 2), sigma=shift, which="LM", tol=1e-12)
    return lam, V, scale


#: Inverse iteration of the candidates: the shift in units of round-off of the largest
#: stiffness (``eps * scale``; a shift this small makes ``Ks + shift I`` nearly singular,
#: which inverse iteration wants, but not exactly), and the steps. A shift of ``1e-9 scale``
#: (before) sat above the softest elastic mode of a gear pair on 1e12-1e13 N/m supports with
#: nearly massless hubs (mass-scaled 3.7e8 against a shift of 1e12-1e13): the iteration could
#: not separate the drive train's free rotation from it, and the rotation was missed. Beyond
#: about 1e8 between the stiffest and the softest mass-scaled stiffness the rounding of the
#: stiffest part hides the softest mode, and no shift can separate them.
_REFINE_SHIFT = 10.0
_REFINE_STEPS = 8


def _refined(Ks: Any, V: np.ndarray, scale: float, sparse: bool) -> np.ndarray:
    """Inverse iteration just above round-off of zero, then Rayleigh-Ritz: null vectors
    accurate to round-off of the local stiffness, whatever the stiffest part of the model."""
    n = V.shape[0]
    shift = _REFINE_SHIFT * np.finfo(float).eps * scale
    if sparse:
        lu = spla.splu(sp.csc_array(Ks + shift * sp.eye_array(n)))
        solve = lu.solve
    else:
        f = sla.lu_factor(np.asarray(Ks) + shift * np.eye(n))
        solve = lambda b: sla.lu_solve(f, b)  # noqa: E731
    X = V
    for _ in range(_REFINE_STEPS):
        X, _r = np.linalg.qr(solve(X))
    H = X.T @ np.asarray(Ks @ X)
    _, Y = np.linalg.eigh(0.5 * (H + H.T))
    return X @ Y


def find_rigid_modes(system: PeriodicSystem) -> RigidModes | None:
    """The rigid-body modes of ``system`` and their constraint, or None when it has none.

    A rigid-body mode is a null vector of the mean stiffness ``K_0`` that carries mass
    (``r^T M_0 r > 0``). Massless null vectors (a free massless DOF) are a singular model, not a
    rigid body: they are left to the solvers, which refuse them.
    """
    M0, K0 = system.coefficient("M", 0), system.coefficient("K", 0)
    n = system.n
    if M0 is None or n < 2:
        return None
    if K0 is None:  # no stiffness at all: every motion with mass is free
        K0 = sp.csr_array((n, n)) if sp.issparse(M0) else np.zeros((n, n))
    sparse = sp.issparse(M0) or sp.issparse(K0)
    d = np.abs(_diagonal(M0))
    if d.max(initial=0.0) <= 0.0:
        return None
    d = np.maximum(d, 1e-12 * d.max())
    s = 1.0 / np.sqrt(d)
    if sparse:
        Ds = sp.diags_array(s)
        Ks = sp.csr_array(Ds @ sp.csr_array(K0) @ Ds)
    else:
        Ks = s[:, None] * np.asarray(K0, float) * s[None, :]
    lam, V, scale = _candidates(Ks, n)
    if scale == 0.0:  # K_0 = 0: the modes are the directions that carry mass
        if n > DENSE_LIMIT:
            raise ModelError(_TOO_MANY.format(count=n))
        return _constraint(system, M0, s[:, None] * np.eye(n)[:, d > 1e-12 * d.max()], sparse)
    small = np.abs(lam) <= _CANDIDATE * scale
    if not small.any():
        return None
    Vs = _refined(Ks, V[:, small], scale, sparse)
    # the local test: stiffness forces that cancel to round-off (a null vector of K_0 itself,
    # not only of its symmetric part: a circulatory stiffness is not singular)
    absK = abs(Ks) if sparse else np.abs(Ks)
    num = np.linalg.norm(np.asarray(Ks @ Vs), axis=0)
    den = np.linalg.norm(np.asarray(absK @ np.abs(Vs)), axis=0)
    rigid = num <= RIGID_TOL * den
    # ... and in physical units: mass scaling hides the stiffness of (nearly) massless DOFs
    # (a spring on a massless end node of a rigidly moving shaft would pass as free)
    Kp = K0 if sparse else np.asarray(K0, float)
    absKp = abs(sp.csr_array(Kp)) if sparse else np.abs(Kp)
    Rp = s[:, None] * Vs
    num_p = np.linalg.norm(np.asarray(Kp @ Rp), axis=0)
    den_p = np.linalg.norm(np.asarray(absKp @ np.abs(Rp)), axis=0)
    rigid &= num_p <= RIGID_TOL * den_p
    # the Lanczos search sees the modes nearest zero only: when every one it returned is
    # rigid there may be more (a fine mesh's soft elastic modes are candidates too, and the
    # local test above tells them from rigid ones)
    if n > DENSE_LIMIT and small.all() and rigid.all():
        raise ModelError(_TOO_MANY.format(count=small.size))
    Vs = Vs[:, rigid]
    if Vs.shape[1] == 0:
        return None
    return _constraint(system, M0, s[:, None] * Vs, sparse)


def _constraint(system: PeriodicSystem, M0: Any, R: np.ndarray, sparse: bool) -> RigidModes | None:
    """The rigid modes ``R`` (columns, physical units) made ``M_0``-orthonormal, and the
    constraint that holds them (see :class:`RigidModes`)."""
    n = system.n
    d = np.abs(_diagonal(M0))
    s = 1.0 / np.sqrt(np.maximum(d, 1e-12 * d.max()))
    Md = M0 if sparse else np.asarray(M0, float)
    mass = np.einsum("ij,ij->j", R, np.asarray(Md @ R))
    R = R[:, mass > 1e-9 * np.abs(mass).max(initial=0.0)]
    if R.shape[1] == 0:
        return None
    L = sla.cholesky(R.T @ np.asarray(Md @ R), lower=True)
    R = sla.solve_triangular(L, R.T, lower=True).T  # M_0-orthonormal
    R *= np.sign(R[np.argmax(np.abs(R), axis=0), np.arange(R.shape[1])])  # a fixed sign
    C = np.asarray(Md @ R)  # constraint C^T q = 0
    k = R.shape[1]
    varying = _varying_dofs(system)
    Cs = C * s[:, None]  # in mass-scaled units: a scale-free choice
    size = float(np.linalg.norm(Cs, 2))

    def pick(pool: np.ndarray) -> tuple[np.ndarray, float]:
        """Pivots by QR with column pivoting; their quality: the smallest singular value of
        ``C[pivots]`` against ``||C||`` (1 at best; small means a large ``G``)."""
        _, _, piv = sla.qr(Cs[pool].T, pivoting=True, mode="economic")
        chosen = np.sort(pool[piv[:k]])
        return chosen, float(np.linalg.svd(Cs[chosen], compute_uv=False).min()) / size

    pivots, quality = pick(np.arange(n))  # the best-conditioned elimination
    quiet = np.flatnonzero(~varying)  # preferred: no time-varying coefficient there
    if quiet.size >= k and quiet.size < n:
        alt, alt_quality = pick(quiet)
        if alt_quality >= 0.1 * quality:
            pivots, quality = alt, alt_quality
    if not quality > 1e-8:
        return None
    keep = np.setdiff1d(np.arange(n), pivots)
    # C_P^T q_P + C_O^T q_O = 0  ->  q_P = G q_O
    G = -np.linalg.solve(C[pivots].T, C[keep].T)
    G[np.abs(G) <= 1e-14 * np.abs(G).max(initial=0.0)] = 0.0
    return RigidModes(pivots=pivots, keep=keep, G=G, n=n, modes=R)


class FreeBodyError(ModelError):
    """A body has a rigid motion that nothing holds and a steady state cannot hold either (a
    shaft without lateral support): there is no steady state. The message names the body and
    the direction."""


def unheld_motions(system: PeriodicSystem, rigid: RigidModes | None) -> list[FreeMotion]:
    """The directions of ``rigid``'s modes that a steady state may not hold (anything but a
    body's spin and axial translation), named by body; empty when the system does not know its
    bodies (``system.motions`` is None: a system built by hand is held as given)."""
    motions = getattr(system, "motions", None)
    if rigid is None or motions is None:
        return []
    return list(motions.unheld(rigid.modes))


def free_body_message(free: list[FreeMotion], why: str = "") -> str:
    """One sentence naming the free bodies and their directions (``why``: what leaves them
    free, default: no bearing, mesh or link acts on that motion)."""
    order = ("lateral", "tilt", "axial", "spin")
    comps = ("ux", "uy", "uz", "phix", "phiy", "phiz")
    bodies: dict[str, tuple[set[str], set[str]]] = {}
    for f in free:  # one line per body, whatever the number of its free directions
        kinds, names = bodies.setdefault(f.body, (set(), set()))
        kinds.update(f.kinds)
        names.update(f.components)
    what = "; ".join(
        FreeMotion(
            body,
            tuple(k for k in order if k in kinds),
            tuple(sorted(names, key=lambda c: comps.index(c) if c in comps else 6)),
        ).describe()
        for body, (kinds, names) in bodies.items()
    )
    why = why or " (no bearing, mesh or link acts on that motion)"
    return (
        f"bearings: no steady state: {what} with nothing holding it{why}. Support it (add a "
        "bearing); only a drive train's rotation and axial position are held, by the drive "
        "and a thrust bearing (docs/solvers.md)"
    )


def held_rigid_modes(system: PeriodicSystem) -> RigidModes | None:
    """:func:`find_rigid_modes`, refused (:class:`FreeBodyError`) when a mode moves a body in a
    direction a steady state may not hold (:func:`unheld_motions`)."""
    rigid = find_rigid_modes(system)
    free = unheld_motions(system, rigid)
    if free:
        raise FreeBodyError(free_body_message(free))
    return rigid
