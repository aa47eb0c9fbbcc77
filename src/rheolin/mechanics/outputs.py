"""Results per physical item from a Solution and an Assembled model.

Every table is a list of rows ``(harmonic n, frequency [Hz], orders, value)`` for ``n >= 0``;
``orders`` maps each rotating body to ``n w1 / |W_body|`` (the order relative to that shaft).
Complex values are two-sided coefficients: a real signal is ``x(t) = sum_n x_n e^{i n w1 t}``,
so the amplitude of harmonic ``n > 0`` is ``2 |x_n|``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..solution import Solution
from .assembly import Assembled

__all__ = ["HarmonicRow", "bearing_forces", "node_displacements", "transmission_errors"]


@dataclass(frozen=True)
class HarmonicRow:
    """One harmonic of an output: index, frequency [Hz], orders per shaft, complex value(s)."""

    harmonic: int
    frequency_hz: float
    orders: dict[str, float]
    value: np.ndarray


def _row(a: Assembled, n: int, value: np.ndarray) -> HarmonicRow:
    orders = {b: float(n / abs(s)) for b, s in a.plan.spin.items() if s != 0}
    return HarmonicRow(int(n), float(n * a.omega / (2 * np.pi)), orders, value)


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
    dofs = a.dofs(body, node)
    return [_row(a, n, sol.harmonic(n)[dofs]) for n in sol.harmonics if n >= 0]


def bearing_forces(sol: Solution, a: Assembled, name: str) -> list[HarmonicRow]:
    """Force and moment the joint ``name`` exerts on its first node's support, per harmonic.

    ``F_m = sum_n (K_{m-n} + i n w1 D_{m-n}) q_n`` on the joint's DOFs (first six rows: the
    force on the support of node a, i.e. minus the force on the node).
    """
    term = a.joints[name]
    q = {int(n): sol.harmonic(n)[term.dofs] for n in sol.harmonics}
    rows = []
    for m in sol.harmonics:
        if m < 0:
            continue
        F = np.zeros(term.dofs.size, dtype=complex)
        for n, qn in q.items():
            k = int(m - n)
            if k in term.K:
                F += term.K[k] @ qn
            if k in term.D:
                F += 1j * n * a.omega * (term.D[k] @ qn)
        rows.append(_row(a, int(m), F[:6]))
    return rows


def transmission_errors(sol: Solution, a: Assembled, name: str) -> list[HarmonicRow]:
    """Dynamic transmission error ``delta = w^T q`` [m] of mesh ``name`` (line of action)."""
    term, w, _ = a.meshes[name]
    return [
        _row(a, n, np.atleast_1d(w @ sol.harmonic(n)[term.dofs])) for n in sol.harmonics if n >= 0
    ]
