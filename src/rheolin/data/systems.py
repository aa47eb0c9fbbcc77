"""Small built-in periodic systems used by the demo, the docs and the benchmarks."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..system.periodic import PeriodicSystem

__all__ = ["chain_with_mesh"]


def chain_with_mesh(
    n: int = 200,
    *,
    speed: float = 2 * np.pi * 25.0,
    teeth: int = 23,
    mesh_harmonics: int = 5,
    asymmetry: float = 0.1,
    damping_ratio: float = 0.02,
) -> PeriodicSystem:
    """A transmission-like test system: a sparse chain with a gear mesh and an asymmetric body.

    The chain of ``n`` DOF (unit masses, springs ``k = 1e6 N/m``) stands for a shaft line.
    A rank-1 mesh stiffness ``k_m(t) w w^T`` between DOF ``n/3`` and ``2n/3`` varies at the
    mesh frequency ``teeth x speed`` as a rectangular wave with ``mesh_harmonics`` harmonics;
    a 2-DOF block on the last two DOF varies at twice the speed (an asymmetric rotating
    body, relative asymmetry ``asymmetry``). Unbalance loads at ``±1``; the base frequency
    is the shaft speed [rad/s].

    Examples
    --------
    >>> s = chain_with_mesh(30)
    >>> s.n, max(s.coefficient_harmonics)
    (30, 115)
    """
    if n < 6:
        raise ValueError(f"`n` must be >= 6, got {n}")
    k = 1e6
    main = np.full(n, 2 * k)
    main[-1] = k
    K0 = sp.diags([main, -k * np.ones(n - 1), -k * np.ones(n - 1)], [0, 1, -1], format="csr")
    M0 = sp.identity(n, format="csr")
    w_max = 2 * np.sqrt(k)
    D0 = (2 * damping_ratio / w_max) * K0 + 2 * damping_ratio * 50.0 * M0
    a, b = n // 3, (2 * n) // 3
    w = np.zeros(n)
    w[a], w[b] = 1.0, -1.0
    ww = sp.csr_array(np.outer(w, w))
    k_mesh, duty, depth = 0.5 * k, 0.6, 0.3  # mean mesh stiffness, double-contact share, variation
    K: dict[int, object] = {0: sp.csr_array(K0) + k_mesh * ww}
    for j in range(1, mesh_harmonics + 1):
        # rectangular wave: Fourier coefficient of a pulse of width `duty` period, height `depth`
        c = depth * k_mesh * np.sin(np.pi * j * duty) / (np.pi * j)
        K[teeth * j] = c * ww
    kd = asymmetry * k
    block = sp.lil_array((n, n), dtype=complex)
    block[n - 2 : n, n - 2 : n] = kd / 2 * np.array([[1.0, -1j], [-1j, -1.0]])
    K[2] = sp.csr_array(block)
    f1 = np.zeros(n, dtype=complex)
    f1[n - 2 :] = 0.5 * np.array([1.0, -1j])  # rotating unbalance force, unit amplitude
    f_mesh = np.zeros(n, dtype=complex)
    f_mesh[[a, b]] = [1.0, -1.0]  # transmission-error excitation at the mesh frequency
    return PeriodicSystem(
        speed, M={0: M0}, D={0: D0}, K=K, f={1: f1 * speed**2 * 1e-4, teeth: 10.0 * f_mesh}
    )
