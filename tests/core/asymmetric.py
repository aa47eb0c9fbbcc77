"""A catalogue of non-axisymmetric rotors (shared by tests/core/test_asymmetric.py and
bench/asymmetric.py): a shaft-like chain whose last ``fraction`` of nodes turns with a
stiffness asymmetry ``Delta K / K``, Rayleigh damping ``zeta`` over its band of modes."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

import rheolin as rl

#: Delta K / K (= 2 k_d / k) of the catalogue.
ASYMMETRIES = (0.01, 0.05, 0.10, 0.20)
#: Share of the shaft's nodes that are non-axisymmetric.
FRACTIONS = (0.1, 0.3, 1.0)
#: Damping ratios at both ends of the band of modes.
DAMPINGS = (0.005, 0.02, 0.05)
#: Speeds [rad/s]: below, inside and above the band of modes (~1000-3200 rad/s).
SPEEDS = (500.0, 1500.0, 4000.0)
#: Modes up to this frequency [rad/s] get harmonics around them.
BAND_TOP = 3500.0


def shaft(
    nodes: int, asymmetry: float, fraction: float, zeta: float, speed: float, planes: bool = False
):
    """``(system, harmonics)``: 2 DOF (x, y) per node, nearest and next-nearest springs, an
    elastic foundation, unit masses; the rotating asymmetry in the inertial frame is
    ``k_d [[cos 2Wt, sin 2Wt], [sin 2Wt, -cos 2Wt]]`` on each turning node (the asymmetric
    Jeffcott rotor's, node by node), with ``k_d = asymmetry x k_local / 2``; unbalance in
    the middle of the asymmetric part."""
    n = 2 * nodes
    k1, k2, kg = 2e6, 5e5, 1e6
    rows, cols, vals = [], [], []
    for d in (0, 1):
        dof = 2 * np.arange(nodes) + d
        for a, b, k in ((dof[:-1], dof[1:], k1), (dof[:-2], dof[2:], k2)):
            rows += [a, b, a, b]
            cols += [a, b, b, a]
            vals += [
                np.full(a.size, k),
                np.full(a.size, k),
                np.full(a.size, -k),
                np.full(a.size, -k),
            ]
    K = sp.coo_array(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
    ).tocsr() + kg * sp.eye_array(n, format="csr")
    M = sp.eye_array(n, format="csr")
    w_lo, w_hi = 1000.0, 3200.0
    beta = 2 * zeta / (w_lo + w_hi)
    D = sp.csr_array(beta * w_lo * w_hi * M + beta * K)
    kd = 0.5 * asymmetry * (kg + 2 * k1 + 2 * k2)
    block = kd * (np.array([[1.0, 0.0], [0.0, -1.0]]) / 2 + np.array([[0.0, 1.0], [1.0, 0.0]]) / 2j)
    K2 = sp.lil_array((n, n), dtype=complex)
    turning = range(nodes - max(1, round(fraction * nodes)), nodes)
    for node in turning:
        K2[2 * node : 2 * node + 2, 2 * node : 2 * node + 2] = block
    f1 = np.zeros(n, complex)
    at = turning[len(turning) // 2]  # the middle of the asymmetric part
    f1[2 * at : 2 * at + 2] = [1.0, -1j]
    system = rl.PeriodicSystem(speed, M={0: M}, D={0: D}, K={0: K, 2: sp.csr_array(K2)}, f={1: f1})
    if planes:  # the (x, y) plane of every node: the whirl-pair preconditioner may use them
        system.whirl_pairs = (2 * np.arange(nodes), 2 * np.arange(nodes) + 1)
    return system, rl.HarmonicSet.full(int(np.ceil(BAND_TOP / speed)) + 4)
