"""An independent Floquet reference for stiff periodic systems: the monodromy matrix.

``M(t) q'' + D(t) q' + K(t) q = 0`` is written as ``E(t) y' = F(t) y`` with ``y = (q, v)``,
``E = diag(I, M)``, ``F = [[0, I], [-K, -D]]``, and integrated over its period
``T = 2 pi / w1`` from every unit vector at once by the three-stage Radau IIA collocation
method (order 5, L-stable; Hairer and Wanner, *Solving ODEs II*, IV.5) with a fixed step.
Nothing of Hill's method enters: no harmonic truncation, no eigenvalue selection, no
lattice. The largest Floquet real part is ``log max |mu| / T`` over the eigenvalues ``mu`` of
the monodromy matrix.

Why not DOP853 as in ``test_lattice.monodromy_max_real``: a gearbox has modes up to 5e5 rad/s
next to the few hundred rad/s that resonate, and an explicit method's step is bound by the
stiffest one (10^5 steps of a 144 x 144 matrix ODE per period). L-stability lets the step
follow the time variation of the coefficients instead (the fourth mesh harmonic), and maps
the stiff modes to multipliers near zero, where they cannot pass for the leading one. (A
Magnus integrator diverges here: its series needs ``h ||A|| < pi``.)

The step is cheap because of two structures of a gearbox:

* The constant part is diagonal in the modal coordinates of the time-averaged pencil
  ``(F_0, E_0)`` (``z = V^-1 y``, ``W^H E_0 V = I``): its share of the stage equations is a
  3 x 3 solve per mode.
* The time variation (mesh stiffness, a flatted shaft, rotating bodies) touches a few DOFs
  ``S`` (44 of 72 on the coarse gearbox variant). The stage equations are solved exactly for
  the ``3 |S|`` values the variation produces (a Woodbury-style reduction), then the modal
  stage derivatives follow.

The error is estimated by halving the step (:func:`leading_real`): the difference of the
two results. (Order 5 would make it 31 times the finer one's error, but with 2000 steps per
period the fourth mesh harmonic has fewer than two steps per cycle: the ratio is not yet
32, so the plain difference is taken.)
Checked against DOP853 on the two-mesh chain and Mathieu's equation (test_w30_references.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

import rheolin as rl

__all__ = ["Reference", "leading_real", "monodromy", "unstable_edge"]

_S6 = np.sqrt(6.0)
#: Radau IIA, three stages: the Butcher matrix (its last row is ``b``) and the nodes.
RADAU_A = np.array(
    [
        [(88 - 7 * _S6) / 360, (296 - 169 * _S6) / 1800, (-2 + 3 * _S6) / 225],
        [(296 + 169 * _S6) / 1800, (88 + 7 * _S6) / 360, (-2 - 3 * _S6) / 225],
        [(16 - _S6) / 36, (16 + _S6) / 36, 1 / 9],
    ]
)
RADAU_C = np.array([(4 - _S6) / 10, (4 + _S6) / 10, 1.0])


def _dense(x: object) -> np.ndarray:
    return x.toarray() if hasattr(x, "toarray") else np.asarray(x)  # type: ignore[attr-defined]


def monodromy(system: rl.PeriodicSystem, steps: int) -> tuple[np.ndarray, float]:
    """The monodromy matrix over one period (in the modal coordinates of the averaged
    pencil: the same eigenvalues) and the period ``T``, by ``steps`` Radau IIA steps."""
    n, w = system.n, system.omega
    T = 2 * np.pi / w
    zero = np.zeros((n, n))
    M0, D0, K0 = (_dense(getattr(system, x).get(0, zero)) for x in "MDK")
    E0 = np.block([[np.eye(n), zero], [zero, M0]])
    F0 = np.block([[zero, np.eye(n)], [-K0, -D0]])
    lam, WL, V = sla.eig(F0, E0, left=True, right=True)
    WH = WL.conj().T
    WH = WH / np.diag(WH @ E0 @ V)[:, None]  # W^H E0 V = I
    varying = {x: {k: _dense(v) for k, v in getattr(system, x).items() if k != 0} for x in "MDK"}
    touched = {
        int(i)
        for table in varying.values()
        for m in table.values()
        for i in np.flatnonzero(np.abs(m).sum(axis=0) + np.abs(m).sum(axis=1))
    }
    S = np.array(sorted(touched), dtype=int)
    r = S.size
    Wl = WH[:, n + S]  # the modal rows of the v equations at S
    Vq, Vv = V[S, :], V[n + S, :]
    tables = {}
    for x in "MDK":
        ks = sorted(varying[x])
        coef = np.array([varying[x][k][np.ix_(S, S)].ravel() for k in ks]).reshape(len(ks), r * r)
        tables[x] = (np.array(ks, dtype=float), coef)

    def at(x: str, ts: np.ndarray) -> np.ndarray:
        ks, coef = tables[x]
        if ks.size == 0:
            return np.zeros((ts.size, r, r))
        return (np.exp(1j * w * np.outer(ts, ks)) @ coef).real.reshape(ts.size, r, r)

    h = T / steps
    A = RADAU_A
    # per mode, the stage matrix of the constant part: (I - h lam A)^-1
    Minv = np.linalg.inv(np.eye(3)[None] - h * lam[:, None, None] * A[None])
    # the varying DOFs' values of the modal stage derivatives, per unit of each stage's
    # variation product: P_ij = V_S diag(Minv[:, i, j]) Wl, and h sum_l a_il P_lj
    Pq = np.einsum("am,mij,mb->ijab", Vq, Minv, Wl)
    Pv = np.einsum("am,mij,mb->ijab", Vv, Minv, Wl)
    Qq = h * np.einsum("il,ljab->ijab", A, Pq)
    Qv = h * np.einsum("il,ljab->ijab", A, Pv)
    g = Minv.sum(axis=2) * lam[:, None]  # frozen stage derivatives per unit of z: (2n, 3)
    frozen = 1.0 + h * (g @ A[2])
    mix = h * np.einsum("i,mij->mj", A[2], Minv)
    Phi = np.eye(2 * n, dtype=complex)
    big = np.empty((3 * r, 3 * r), dtype=complex)
    rhs = np.empty((3 * r, 2 * n), dtype=complex)
    for step in range(steps):
        ts = step * h + RADAU_C * h
        dK, dD, dM = at("K", ts), at("D", ts), at("M", ts)
        for i in range(3):
            rows = slice(i * r, (i + 1) * r)
            for j in range(3):
                # c_i = -dK q_i - dD v_i - dM kappa_v,i at S, linear in every c_j
                big[rows, j * r : (j + 1) * r] = (
                    dK[i] @ Qq[i, j] + dD[i] @ Qv[i, j] + dM[i] @ Pv[i, j]
                )
            coef = 1.0 + h * (g @ A[i])
            rhs[rows] = -(dK[i] @ (Vq * coef) + dD[i] @ (Vv * coef) + dM[i] @ (Vv * g[:, i]))
        big[np.diag_indices(3 * r)] += 1.0
        C = np.linalg.solve(big, rhs @ Phi)
        new = frozen[:, None] * Phi
        for j in range(3):
            new += mix[:, j][:, None] * (Wl @ C[j * r : (j + 1) * r])
        Phi = new
    return Phi, T


def _leading(system: rl.PeriodicSystem, steps: int) -> float:
    Phi, T = monodromy(system, steps)
    mu = np.abs(np.linalg.eigvals(Phi))
    return float(np.log(mu.max()) / T)


@dataclass(frozen=True)
class Reference:
    """The largest Floquet real part from the monodromy matrix.

    Attributes
    ----------
    value
        From ``steps`` steps [1/s].
    error
        Estimated error of ``value``: ``|value - coarse|``, with ``coarse`` from half the
        steps.
    steps
        Radau steps per period.
    """

    value: float
    error: float
    steps: int


def leading_real(system: rl.PeriodicSystem, steps: int = 2000) -> Reference:
    """The largest Floquet real part of ``system`` with an error estimate (two step sizes)."""
    fine = _leading(system, steps)
    coarse = _leading(system, steps // 2)
    return Reference(fine, abs(fine - coarse), steps)


def unstable_edge(
    model: rl.Model,
    stable_rpm: float,
    unstable_rpm: float,
    *,
    steps: tuple[int, ...] = (2000, 4000, 8000),
    rtol: float = 1e-8,
) -> tuple[float, float, int]:
    """The speed [rpm] between the two where the largest Floquet real part of ``model``
    crosses zero, its uncertainty [rpm] and the number of monodromy matrices it took.

    Brent's method on the reference with ``steps[0]`` steps per period finds the crossing
    to ``rtol`` (relative); secant steps from there move it to the crossings with the finer
    steps, and the uncertainty is the last move (what halving the step changed) plus
    ``rtol``.
    """
    from scipy.optimize import brentq

    count = [0]

    def f(rpm: float, n: int) -> float:
        count[0] += 1
        return _leading(model.assemble(rpm * np.pi / 30).system, n)

    lo, hi = sorted((stable_rpm, unstable_rpm))
    root = float(brentq(f, lo, hi, args=(steps[0],), xtol=1e-6 * hi, rtol=4 * np.finfo(float).eps))
    roots = [root]
    width = 1e-4 * root  # the secant's first pair
    for n in steps[1:]:
        a, b = root - width, root + width
        fa, fb = f(a, n), f(b, n)
        for _ in range(8):
            if fb == fa:
                break
            c = b - fb * (b - a) / (fb - fa)
            if abs(c - b) <= rtol * abs(c):
                b = c
                break
            a, fa, b, fb = b, fb, c, f(c, n)
        width = max(abs(b - root), 10 * rtol * root)
        root = float(b)
        roots.append(root)
    error = abs(roots[-1] - roots[-2]) if len(roots) > 1 else float("nan")
    return root, error + rtol * root, count[0]
