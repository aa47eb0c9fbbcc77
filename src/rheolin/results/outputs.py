"""Results per physical item from a Solution and an Assembled model.

Every table is a list of rows ``(harmonic n, frequency [Hz], orders, value)`` for ``n >= 0``;
``orders`` maps each rotating body to ``n w1 / |W_body|`` (the order relative to that shaft).
Complex values are two-sided coefficients: a real signal is ``x(t) = sum_n x_n e^{i n w1 t}``,
so the amplitude of harmonic ``n > 0`` is ``2 |x_n|``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mechanics.assembly import Assembled
from ..solvers.solution import Solution

__all__ = [
    "HarmonicRow",
    "bearing_force_array",
    "bearing_forces",
    "global_displacements",
    "node_displacements",
    "transmission_error_array",
    "transmission_errors",
]


@dataclass(frozen=True)
class HarmonicRow:
    """One harmonic of an output: index, frequency [Hz], orders per shaft, complex value(s)."""

    harmonic: int
    frequency_hz: float
    orders: dict[str, float]
    value: np.ndarray


def _rows(a: Assembled, harmonics: np.ndarray, values: np.ndarray) -> list[HarmonicRow]:
    spins = [(b, abs(s)) for b, s in a.plan.spin.items() if s != 0]
    return [
        HarmonicRow(
            int(n), float(n * a.omega / (2 * np.pi)), {b: float(n / s) for b, s in spins}, v
        )
        for n, v in zip(harmonics.tolist(), values, strict=True)
    ]


def _half(sol: Solution, dofs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The harmonics ``n >= 0`` of the solution and ``q_n`` on ``dofs`` (one row each)."""
    keep = sol.harmonics >= 0
    return sol.harmonics[keep], sol.q[keep][:, dofs]


def _convolve(sol: Solution, series: dict, dofs: np.ndarray | None = None) -> np.ndarray:
    """``y_n = sum_k X_k q_{n-k}`` for the harmonics ``n >= 0`` of the solution (``X_k``
    matrices or sparse arrays acting on ``q``, or vectors: then ``y_n = X_k^T q``)."""
    H = sol.harmonics
    m = H[H >= 0]
    Q = sol.q if dofs is None else sol.q[:, dofs]
    out: np.ndarray | None = None
    for k, X in series.items():
        n = m - k
        j = np.clip(np.searchsorted(H, n), 0, H.size - 1)
        hit = H[j] == n
        part = Q[j[hit]] @ (X.T if getattr(X, "ndim", 1) == 2 else X)
        if out is None:
            out = np.zeros((m.size, *part.shape[1:]), dtype=complex)
        out[hit] += part
    assert out is not None
    return out


def global_displacements(sol: Solution, a: Assembled) -> np.ndarray:
    """``q_n`` (``n >= 0``, every DOF) in global axes: the DOFs of bodies written in a planetary
    set's carrier axes (docs/planetary.md) turned back, ``q = T(t) z``.

    >>> import rheolin as rl
    >>> from rheolin.mechanics.model import Model
    >>> m = Model()
    >>> m.add_rigid_body("r", (0, 0, 0), 1.0, (1e-3, 1e-3, 2e-3))
    >>> m.add_bearing("b", "r", 0, 1e6, 10.0, components=None)
    >>> m.add_force("f", "r", 0, force=(1.0, 0, 0), order=1)
    >>> a = m.assemble(100.0)
    >>> sol = rl.solve(a.system, [1])
    >>> bool(np.allclose(global_displacements(sol, a), sol.q[sol.harmonics >= 0]))
    True
    """
    if a.frames is None:
        return sol.q[sol.harmonics >= 0]
    return _convolve(sol, a.frames.rotation(a.system.n))


def node_displacements(sol: Solution, a: Assembled, body: str, node: int) -> list[HarmonicRow]:
    """Harmonics of ``(ux, uy, uz, phix, phiy, phiz)`` of one node.

    Examples
    --------
    >>> import rheolin as rl
    >>> from rheolin.mechanics.model import Model
    >>> m = Model()
    >>> m.add_rigid_body("r", (0, 0, 0), 1.0, (1e-3, 1e-3, 2e-3))
    >>> m.add_disk("r", 0, unbalance=1e-4)
    >>> m.add_bearing("b", "r", 0, 1e6, 10.0, components=None)
    >>> a = m.assemble(100.0)
    >>> rows = node_displacements(rl.solve(a.system, [1]), a, "r", 0)
    >>> rows[0].harmonic, round(rows[0].frequency_hz, 3), rows[0].orders
    (1, 15.915, {'r': 1.0})
    """
    if a.frames is not None:
        return _rows(
            a,
            sol.harmonics[sol.harmonics >= 0],
            global_displacements(sol, a)[:, a.dofs(body, node)],
        )
    return _rows(a, *_half(sol, a.dofs(body, node)))


def bearing_force_array(sol: Solution, a: Assembled, name: str) -> tuple[np.ndarray, np.ndarray]:
    """:func:`bearing_forces` as arrays: the harmonics ``m >= 0`` and ``F_m`` (shape (., 6)).

    One product per coefficient harmonic ``k`` of the joint over every ``m`` at once.
    """
    term = a.joints[name]
    H = sol.harmonics
    pos = H >= 0
    Q = sol.q[:, term.dofs]
    F = np.zeros((int(pos.sum()), term.dofs.size), dtype=complex)
    m = H[pos]
    for k in set(term.K) | set(term.D):
        n = m - k
        j = np.clip(np.searchsorted(H, n), 0, H.size - 1)
        hit = H[j] == n
        if not hit.any():
            continue
        Qn = Q[j[hit]]
        acc = np.zeros((Qn.shape[0], term.dofs.size), dtype=complex)
        if k in term.K:
            acc += Qn @ np.asarray(term.K[k]).T
        if k in term.D:
            s = 1j * a.omega * n[hit].astype(float)
            acc += s[:, None] * (Qn @ np.asarray(term.D[k]).T)
        F[hit] += acc
    pre = term.f.get(0)
    if pre is not None:  # a preloaded joint: preload + K delta (the load on the node is -T^T p)
        F[m == 0, :6] -= np.asarray(pre)[:6]
    return m, F[:, :6]


def bearing_forces(sol: Solution, a: Assembled, name: str) -> list[HarmonicRow]:
    """Force and moment the joint ``name`` exerts on its first node's support, per harmonic.

    ``F_m = sum_n (K_{m-n} + i n w1 D_{m-n}) q_n`` on the joint's DOFs (first six rows: the
    force on the support of node a, i.e. minus the force on the node).
    """
    return _rows(a, *bearing_force_array(sol, a, name))


def transmission_error_array(
    sol: Solution, a: Assembled, name: str
) -> tuple[np.ndarray, np.ndarray]:
    """The harmonics ``n >= 0`` and ``delta_n = w^T q_n`` [m] of mesh ``name`` (a mesh whose
    ``w`` turns, ``{k: w_k}``: ``delta_n = sum_k w_k^T q_{n-k}``)."""
    term, w, _ = a.meshes[name]
    if isinstance(w, dict):
        return sol.harmonics[sol.harmonics >= 0], _convolve(sol, w, term.dofs)
    n, Q = _half(sol, term.dofs)
    return n, Q @ w


def transmission_errors(sol: Solution, a: Assembled, name: str) -> list[HarmonicRow]:
    """Dynamic transmission error ``delta = w^T q`` [m] of mesh ``name`` (line of action)."""
    n, delta = transmission_error_array(sol, a, name)
    return _rows(a, n, delta[:, None])
