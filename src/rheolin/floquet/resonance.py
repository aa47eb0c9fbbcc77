"""Step costs that see resonance: the lattice of a Floquet search.

The lattice's step costs (:func:`~rheolin.harmonics.lattice.coupling_costs`) rank the
coefficient harmonics by the strength of their couplings. What an eigenvector carries at
harmonic ``k`` is, to first order, the coupling over the *detuning*: starting from the
time-averaged mode ``j`` at harmonic 0, its component along mode ``m`` at harmonic ``k`` is

    a_k = |w_m^H E_k(lambda_j) x_j| / |lambda_j + i k w1 - lambda_m|

(``E_k = A_k - lambda_j B_k``, the balanced first-order coupling; ``W^H B_0 X = I``). A weak
coupling near a resonance (a polymer gear mesh at twice a mode it carries: ``a_k`` = 7 where
the strongest coupling's is 2.5) is what decides the verdict there, yet its strength puts it
at cost 3: at orders 1-3 the growing exponent is not resolved, the verdict stays undecided and
the largest real part is the mode's undisturbed damping.

:func:`resonant_costs` therefore lowers a step's cost to what its largest first-order
amplitude says, ``1 + floor(log10(a_max / a_k))`` like the coupling costs, over the modes whose
Gershgorin discs reach the axis (the others cannot change the verdict; the heavily damped ones
would lower costs to no purpose); a cost is never raised, so a lattice of a given order only
gains harmonics (docs/stability.md, section 2).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..harmonics.hill import scaled_entries
from ..harmonics.lattice import Lattice, coupling_costs, harmonic_lattice
from ..system.periodic import PeriodicSystem
from .averaged import Averaged
from .band import time_averaged

__all__ = [
    "averaged_modes",
    "first_order_amplitudes",
    "floquet_lattice",
    "resonant_costs",
]


def averaged_modes(system: PeriodicSystem) -> Averaged:
    """The time-averaged modes of ``system`` (all of them, or the band of a large model:
    :func:`~rheolin.floquet.band.time_averaged`), made once and kept on it (the lattice's
    costs and the search use the same)."""
    return system.cached("floquet.averaged", lambda: time_averaged(system))


def first_order_amplitudes(
    system: PeriodicSystem, avg: Averaged, modes: np.ndarray
) -> dict[int, float]:
    """``a_k`` (module docstring) for every positive coefficient harmonic ``k``: the largest
    over the source ``modes`` (indices into ``avg.lam``), every target mode and both signs
    of ``k``.

    >>> import numpy as np, rheolin as rl
    >>> s = rl.PeriodicSystem(1.9, M={0: np.eye(1)}, D={0: 0.02 * np.eye(1)},
    ...                       K={0: np.eye(1), 1: 0.05 * np.eye(1)})
    >>> avg = Averaged(s)
    >>> a = first_order_amplitudes(s, avg, np.arange(2))[1]
    >>> bool(0.2 < a < 0.3)  # 2 x 1 rad/s ~ 1.9: near the principal resonance
    True
    """
    n, w = system.n, system.omega
    iq, iv = 1.0 / avg.sq, 1.0 / avg.sv
    lam, X, W = avg.lam, avg.X, avg.W
    src = np.asarray(modes, dtype=int)
    out: dict[int, float] = {}
    if src.size == 0:
        return out
    lj = lam[src]
    for k in system.coefficient_harmonics:
        if k == 0:
            continue
        # the v rows of E_k: -(K_k x_q + (D_k + lambda_j M_k) x_v) on a few DOFs
        total = np.zeros((n, src.size), dtype=complex)
        for table, right, off, scale in (
            (system.K, iq, 0, None),
            (system.D, iv, n, None),
            (system.M, iv, n, lj),
        ):
            x = table.get(k)
            if x is None:
                continue
            r, c, v = scaled_entries(x, iv, right)
            contrib = v[:, None] * X[off + c][:, src]
            if scale is not None:
                contrib = contrib * scale[None, :]
            np.add.at(total, r, contrib)
        rows = np.flatnonzero(np.any(total != 0, axis=1))
        if not rows.size:
            continue
        c_mj = W[n + rows].conj().T @ total[rows]  # (every mode m, source j)
        detuning = np.abs(lj[None, :] + 1j * k * w - lam[:, None])
        with np.errstate(divide="ignore", invalid="ignore"):
            a = np.abs(c_mj) / detuning
        a = float(np.nanmax(np.where(np.isfinite(a), a, np.inf), initial=0.0))
        out[abs(int(k))] = max(out.get(abs(int(k)), 0.0), a)
    return out


def resonant_costs(system: PeriodicSystem, avg: Averaged | None = None) -> dict[int, int]:
    """The coupling costs with each step lowered to its first-order amplitude's cost (module
    docstring); the coupling costs unchanged when no mode's disc reaches the axis.

    >>> import numpy as np, rheolin as rl
    >>> from rheolin.harmonics.lattice import coupling_costs
    >>> K = {0: np.diag([1.0, 4.0]), 1: np.diag([0.0, 0.4]), 7: np.diag([0.0015, 0.0])}
    >>> s = rl.PeriodicSystem(0.2857, M={0: np.eye(2)}, D={0: np.diag([0.002, 0.02])}, K=K)
    >>> coupling_costs(s), resonant_costs(s)  # 7 w1 = 2.0 ~ twice the first mode
    ({1: 1, 7: 3}, {1: 1, 7: 1})
    """
    base = coupling_costs(system)
    if not base:
        return base
    avg = averaged_modes(system) if avg is None else avg
    up = np.flatnonzero(avg.lam.imag >= -1e-9 * np.maximum(np.abs(avg.lam), system.omega))
    radii = np.asarray(avg.gershgorin(system, [int(m) for m in up]))
    reach = up[avg.lam[up].real + radii >= 0]
    amps = first_order_amplitudes(system, avg, reach)
    known = {k: a for k, a in amps.items() if k in base and a > 0}
    if not known:
        return base
    top = max(known.values())
    out = dict(base)
    for k, a in known.items():
        out[k] = min(base[k], 1 + int(np.floor(np.log10(top / a) + 1e-9)))
    return out


def floquet_lattice(
    system: PeriodicSystem, order: int, *, max_size: int | None = None, avg: Any = None
) -> Any:
    """The lattice of order ``order`` on :func:`resonant_costs` (the coupling costs when the
    time-averaged modes cannot be computed densely); ``avg``: the time-averaged modes the
    search starts from (a large model's certified band), else :func:`averaged_modes`."""
    try:
        costs = resonant_costs(system, avg)
    except ValueError:  # too large for the dense averaged modes
        costs = coupling_costs(system)
    if not costs:
        return harmonic_lattice({}, 0)
    lattice: Lattice = harmonic_lattice(costs, order, max_size=max_size)
    return lattice
