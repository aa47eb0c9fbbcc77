"""Undamped critical-speed map: the synchronous critical speeds against bearing stiffness.

The classical design chart of rotordynamics (API 684): every bearing's transverse stiffness is
set to one value ``k`` (isotropic, no cross-coupling, no damping), and the speeds ``W`` where a
mode whirls forward in step with the input shaft are found directly. With the time-averaged
coefficients ``M``, ``K(W) = K_0 + W^2 K_2`` (spin softening) and the gyroscopic matrix
``W G``, synchronous forward whirl ``q = x exp(i W t)`` needs

    ( K_0 - W^2 (M - i G - K_2) ) x = 0,

a generalized eigenproblem in ``W^2`` (real and positive for a conservative rotor). Damping and
circulatory terms are left out (undamped map). Low ``k``: rigid-body modes on soft supports
(``W`` grows as ``sqrt(k)``); high ``k``: the shaft's pinned-pinned bending criticals.

>>> import numpy as np
>>> from rheolin.mechanics import Model
>>> m = Model()
>>> m.add_shaft("s", [0.0, 0.25, 0.5], outer_diameter=0.05, material="steel")
>>> m.add_disk("s", 1, mass=20.0, inertia=[0.2, 0.2, 0.1])
>>> for k in (0, 2):
...     m.add_bearing(f"b{k}", "s", k, stiffness=1e6)
>>> cmap = critical_speed_map(m, [1e5, 1e6])
>>> cmap.speeds.shape
(2, 4)
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import ModelError
from ..mechanics.rotation import transverse_basis
from .modes import WHIRL_THRESHOLD

__all__ = ["CriticalSpeedMap", "critical_speed_map", "synchronous_critical_speeds"]


@dataclass
class CriticalSpeedMap:
    """Undamped synchronous critical speeds [rad/s] against bearing stiffness [N/m].

    Attributes
    ----------
    stiffness
        Bearing stiffness values, shape ``(n_k,)``.
    speeds
        The lowest critical speeds at each stiffness, shape ``(n_k, n_modes)`` (NaN: fewer).
    bearings
        The bearings whose transverse stiffness was set.
    actual
        ``{bearing: its own transverse stiffness}`` (the mean of its two transverse direct
        terms), to mark the operating point on the map.
    """

    stiffness: np.ndarray
    speeds: np.ndarray
    bearings: list[str]
    actual: dict[str, float] = field(default_factory=dict)

    def to_dataset(self) -> Any:
        """The map as an ``xarray.Dataset`` (speeds in rad/s, ``critical_speed_rpm`` beside).

        >>> r = CriticalSpeedMap(np.array([1e6]), np.array([[100.0, 200.0]]), ["b"], {"b": 1e6})
        >>> r.to_dataset()["critical_speed"].dims
        ('stiffness', 'mode')
        """
        import xarray as xr

        return xr.Dataset(
            {
                "critical_speed": (
                    ("stiffness", "mode"),
                    self.speeds,
                    {"units": "rad/s", "long_name": "undamped synchronous critical speed"},
                ),
                "critical_speed_rpm": (
                    ("stiffness", "mode"),
                    self.speeds * 30 / np.pi,
                    {"units": "rpm"},
                ),
                "actual_stiffness": (
                    ("bearing",),
                    [self.actual.get(b, np.nan) for b in self.bearings],
                    {"units": "N/m"},
                ),
            },
            coords={
                "stiffness": ("stiffness", self.stiffness, {"units": "N/m"}),
                "mode": ("mode", np.arange(self.speeds.shape[1]), {"units": "1"}),
                "bearing": list(self.bearings),
            },
        )


def _averaged_parts(model: Any) -> tuple[Any, ...]:
    """``(M, K_0, K_2, G, T, assembled)`` of the time-averaged system, by speed
    (``K = K_0 + W K_1 + W^2 K_2``, ``D = D_0 + W G``) from the model's speed template at
    three speeds, reduced by
    ``T`` when the model has a free axial or torsional motion (held: no critical speed at 0);
    sparse (CSC)."""
    from ..system.rigid_modes import find_rigid_modes

    W = np.array([1.0, 2.0, 3.0])
    template = model.speed_template()
    built = [template.assemble(float(w)) for w in W]
    mats = [b.system for b in built]

    def part(s: Any, name: str) -> sp.csc_array:
        x = getattr(s, name).get(0)
        return sp.csc_array((s.n, s.n)) if x is None else sp.csc_array(x)

    link = mats[0].constraint
    Tc = sp.identity(mats[0].n, format="csr") if link is None else link.transform()
    if link is not None:  # rigid links: eliminated
        mats = [link.reduce(s) for s in mats]
    M = part(mats[0], "M")
    K = [part(s, "K") for s in mats]
    D = [part(s, "D") for s in mats]
    rigid = find_rigid_modes(mats[0])
    T = sp.identity(M.shape[0], format="csr") if rigid is None else sp.csr_array(rigid.transform())
    M, K, D = T.T @ M @ T, [T.T @ k @ T for k in K], [T.T @ d @ T for d in D]
    T = sp.csr_array(Tc @ T)  # from the reduced coordinates to every DOF
    c = np.linalg.inv(np.vander(W, 3, increasing=True))  # rows: [1, W, W^2] coefficients
    K0 = sp.csc_array(sum(c[0, i] * K[i] for i in range(3)))
    K2 = sp.csc_array(sum(c[2, i] * K[i] for i in range(3)))
    G = sp.csc_array((D[1] - D[0]) / (W[1] - W[0]))
    return sp.csc_array(M), K0, K2, G, T, built[0]


#: Up to this many unknowns the pencil's roots all come by QZ (dense); above, the lowest by
#: shift-invert Arnoldi on a sparse LU of ``K_0`` (:class:`_LowestRoots`), their number
#: doubled while they hold fewer critical speeds than asked, up to ``MAX_ROOTS`` (a model
#: whose lowest roots mostly do not whirl then has the critical speeds below its
#: ``MAX_ROOTS``-th root only).
DENSE_CRITICAL = 600
MAX_ROOTS = 512


def _all_roots(K0: Any, B: Any) -> tuple[np.ndarray, np.ndarray]:
    """Every root ``W^2`` of ``(K_0 - W^2 B) x = 0`` and its vector, by QZ."""
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        mu, X = sla.eig(K0.toarray(), B.toarray())
    return mu, X


class _LowestRoots:
    """The roots ``W^2`` of ``(K_0 - W^2 B) x = 0`` nearest a shift ``sigma <= 0`` (0, or just
    below where ``K_0`` is singular; ``scale`` is ``||K_0|| / ||B||``), by Arnoldi on
    ``(K_0 - sigma B)^-1 B`` through one sparse LU, factorized once for every run."""

    def __init__(self, K0: Any, B: Any, scale: float) -> None:
        for sigma in (0.0, -1e-6 * scale, -1e-3 * scale):
            try:
                lu = spla.splu(sp.csc_array(K0 - sigma * B).astype(complex))
            except RuntimeError:  # exactly singular
                continue
            break
        else:
            raise ModelError("critical speeds: the time-averaged stiffness is singular")
        n = K0.shape[0]
        self.sigma = sigma
        self.op = spla.LinearOperator((n, n), matvec=lambda x: lu.solve(B @ x), dtype=complex)

    def __call__(self, k: int) -> tuple[np.ndarray, np.ndarray, float]:
        """The ``k`` nearest roots, their vectors and ``top``: with ``r`` the largest
        ``|W^2 - sigma|`` among them, every root closer than ``r`` to ``sigma`` is one of
        them, so every positive real root below ``r + sigma = top`` is."""
        n, sigma = self.op.shape[0], self.sigma
        v0 = np.random.default_rng(7).standard_normal(n) + 0j
        theta, X = spla.eigs(self.op, k=k, which="LM", ncv=min(n - 1, max(2 * k + 1, 40)),
                             tol=1e-13, v0=v0)  # fmt: skip
        with np.errstate(divide="ignore"):
            mu = sigma + 1.0 / theta
        radius = float(np.max(np.abs(mu - sigma)))
        return mu, X, radius + sigma


#: Critical speeds closer than this (relative) are one: the two planes of an isotropic rotor.
SAME = 1e-6


def synchronous_critical_speeds(model: Any, n_modes: int = 4) -> np.ndarray:
    """The lowest undamped forward synchronous critical speeds [rad/s] of ``model`` (its
    damping and circulatory terms left out; see the module docstring).

    The eigenvalues ``W^2`` of the pencil come by QZ (above :data:`DENSE_CRITICAL`
    unknowns: the lowest, by shift-invert Arnoldi on a sparse LU, as many as the critical
    speeds asked need); those within ``1e-10 ||K_0|| / ||B||``
    of zero are rigid-body motions (a free axial or torsional motion) and left out, and so
    are solutions that unbalance does not excite: a torsional or axial mode (no whirl), and
    a backward branch crossing the 1x line (whirl ratio at most ``-WHIRL_THRESHOLD``, as
    the Campbell diagram labels it; on isotropic supports unbalance does not excite it at
    all). On anisotropic supports the modes are ellipses, or lines (whirl ratio near 0):
    unbalance excites them, and each is a critical speed, as in the Campbell diagram. The
    two planes of an isotropic rotor give one critical speed: within a group of (nearly)
    equal roots the most forward combination is judged. A rigid rotor of mass ``m`` on two
    bearings ``k`` at ``+-a`` from its centre: translation at ``sqrt(2 k / m)``, tilt at
    ``sqrt(2 k a^2 / (I_d - I_p))`` (none when ``I_p >= I_d``); on supports ``k_x != k_y``
    the translation splits into ``sqrt(2 k_x / m)`` and ``sqrt(2 k_y / m)``.
    """
    M, K0, K2, G, T, built = _averaged_parts(model)
    B = sp.csc_array(M - 1j * G - K2)
    scale = float(spla.norm(K0, 1)) / max(float(spla.norm(B, 1)), 1e-300)
    zero = 1e-10 * scale
    F, Bk = _whirl_maps(model, built)
    n = K0.shape[0]
    k = min(max(4 * n_modes + 8, 24), n - 2)
    lowest = _LowestRoots(K0, B, scale) if n > DENSE_CRITICAL else None
    while True:
        if lowest is None:  # every root
            mu, X = _all_roots(K0, B)
            top = float("inf")
        else:  # the lowest k: a root group is judged only when it lies wholly below the top
            mu, X, below = lowest(k)
            top = below * (1 - 4 * SAME)
        ok = np.isfinite(mu) & (mu.real > zero) & (np.abs(mu.imag) <= 1e-6 * np.abs(mu))
        mu, X = mu[ok].real, X[:, ok]
        order = np.argsort(mu)
        mu, X = mu[order], T @ X[:, order]
        out = _forward_criticals(mu, X, F, Bk, n_modes, top)
        if len(out) >= n_modes or not np.isfinite(top) or k >= MAX_ROOTS:
            return np.array(out)
        k = min(2 * k, n - 2, MAX_ROOTS)


def _forward_criticals(
    mu: np.ndarray, X: np.ndarray, F: Any, Bk: Any, n_modes: int, top: float
) -> list[float]:
    """The critical speeds among the ascending roots ``mu`` (vectors ``X``) below ``top``:
    each group of (nearly) equal roots judged by its most forward combination."""
    out: list[float] = []
    i = 0
    while i < mu.size and len(out) < n_modes:
        j = i + 1
        while j < mu.size and mu[j] <= mu[i] * (1 + 2 * SAME):
            j += 1
        if mu[j - 1] >= top:  # a group the roots found may cut: the next, larger run judges it
            break
        V = X[:, i:j]
        f, b = F @ V, Bk @ V
        Af, Ab = f.conj().T @ f, b.conj().T @ b
        # whirl ratios of the combinations that whirl at all: the pencil (Af - Ab, Af + Ab)
        # on the range of Af + Ab (a coincident axial or torsional root adds no whirl), that
        # range judged against the shapes' own size (a root that does not whirl, computed by
        # Arnoldi, carries rounding's 1e-25 of a whirl, which must not count)
        w, U = np.linalg.eigh(0.5 * (Af + Ab + (Af + Ab).conj().T))
        size = float(np.sum(np.abs(V) ** 2))
        live = w > 1e-10 * max(float(w.max(initial=0.0)), size, 1e-300)
        if live.any():
            P = U[:, live] / np.sqrt(w[live])
            D = P.conj().T @ (Af - Ab) @ P
            if np.linalg.eigvalsh(0.5 * (D + D.conj().T)).max() > -WHIRL_THRESHOLD:
                out.append(float(np.sqrt(mu[i])))
        i = j
    return out


def _whirl_maps(model: Any, built: Any) -> tuple[sp.csr_array, sp.csr_array]:
    """Linear maps from a shape to its forward and backward circles, node by node (the
    transverse translations and tilts of spinning bodies; :func:`~rheolin.stability.modes.
    whirl_ratio` is ``(|F x|^2 - |B x|^2) / (|F x|^2 + |B x|^2)``); sparse, three entries a
    row."""
    labels = built.dof_labels
    index = {lab: i for i, lab in enumerate(labels)}
    rows: list[int] = []
    cols: list[int] = []
    fwd: list[complex] = []
    bwd: list[complex] = []
    count = 0
    for body, node in sorted({(b, i) for b, i, _ in labels}):
        s = built.plan.spin.get(body, 0)
        if s == 0:
            continue
        a, b = transverse_basis(model.bodies[body].axis)
        for kind in (("ux", "uy", "uz"), ("phix", "phiy", "phiz")):
            found = [index.get((body, node, c)) for c in kind]
            if any(r is None for r in found):
                continue
            f, g = a + 1j * b, a - 1j * b
            if s < 0:
                f, g = g, f
            rows += [count] * 3
            cols += [int(r) for r in found if r is not None]
            fwd += f.tolist()
            bwd += g.tolist()
            count += 1
    shape = (count, len(labels))
    return (
        sp.csr_array((np.array(fwd, complex), (rows, cols)), shape=shape),
        sp.csr_array((np.array(bwd, complex), (rows, cols)), shape=shape),
    )


def _ground_bearings(model: Any) -> list[str]:
    """Bearings to ground with a transverse stiffness (an axial or torsional support alone
    is not one: giving it a transverse stiffness would add a support)."""
    out = []
    for name, j in model.joints.items():
        if j["other"][0] is not None or j["table"] is not None:
            continue
        e = np.asarray(model.bodies[j["body"]].axis, float)
        P = np.eye(3) - np.outer(e, e) / (e @ e)
        if np.abs(P @ np.asarray(j["K"])[:3, :3] @ P).max() > 0:
            out.append(name)
    return out


def critical_speed_map(
    model: Any,
    stiffness: Sequence[float] | np.ndarray,
    *,
    bearings: Sequence[str] | None = None,
    n_modes: int = 4,
) -> CriticalSpeedMap:
    """Undamped critical speeds of ``model`` with the transverse stiffness of ``bearings``
    (default: every bearing to ground with a translational stiffness) set to each value of
    ``stiffness`` [N/m] in turn: isotropic across the bearing's body axis, no cross-coupling,
    no damping; their axial and rotational terms are kept. The model itself is not changed.
    """
    from ..mechanics.preload.linearize import linearized

    k = np.asarray(stiffness, dtype=float).ravel()
    if k.size == 0 or not np.all(np.isfinite(k)) or np.any(k <= 0):
        raise ModelError("stiffness: need one or more finite values > 0 [N/m]")
    # a preloaded model: its rolling bearings at their operating stiffness, as linear joints
    model = linearized(model)
    names = _ground_bearings(model) if bearings is None else list(bearings)
    for b in names:
        if b not in model.joints:
            raise ModelError(f"bearings: no bearing {b!r}; bearings: {list(model.joints)}")
        if model.joints[b]["table"] is not None:
            raise ModelError(f"bearings: {b!r} has speed-dependent coefficients (a table)")
    if not names:
        raise ModelError("bearings: the model has no bearing to ground to vary")
    tables = [b for b, j in model.joints.items() if j["table"] is not None]
    if tables:
        raise ModelError(
            f"bearings: {tables} have speed-dependent coefficients, so the synchronous "
            "problem is not an eigenproblem in W^2; use the Campbell diagram's 1x crossings "
            "(rheolin campbell) for this model"
        )
    actual = {}
    for b in names:
        j = model.joints[b]
        e = np.asarray(model.bodies[j["body"]].axis, float)
        P = np.eye(3) - np.outer(e, e)
        actual[b] = float(np.trace(P @ j["K"][:3, :3] @ P) / 2)
    speeds = np.full((k.size, n_modes), np.nan)
    for i, ki in enumerate(k):
        m = copy.deepcopy(model)
        for j in m.joints.values():
            j["D"] = np.zeros((6, 6))
        for b in names:
            j = m.joints[b]
            e = np.asarray(m.bodies[j["body"]].axis, float)
            P = np.eye(3) - np.outer(e, e)
            Kb = np.array(j["K"], dtype=float)
            axial = np.outer(e, e) @ Kb[:3, :3] @ np.outer(e, e)
            Kb[:3, :3] = ki * P + axial
            Kb[:3, 3:] = 0.0
            Kb[3:, :3] = 0.0
            j["K"] = Kb
        w = synchronous_critical_speeds(m, n_modes)
        speeds[i, : w.size] = w
    return CriticalSpeedMap(k, speeds, names, actual)
