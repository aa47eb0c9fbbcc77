"""Many speeds of a time-invariant model in one batched solve (e.g. an unbalance response).

When ``M, D, K`` have no harmonics (axisymmetric rotors on inertial bearings, loads given as
forces), every speed and load harmonic is one independent system
``(K(w1) + s D(w1) + s^2 M) q = f``, ``s = i n w1``, whose coefficients are polynomials in
``w1`` (:class:`~rheolin.mechanics.template.SpeedTemplate`). For a small model all of them
are solved by one batched LAPACK call instead of a Python loop over speeds; each speed's
residual is recomputed independently and reported.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..mechanics.template import SpeedTemplate

__all__ = ["SpeedResponse", "lti_speeds"]

#: Memory for one batch of dense systems (speeds x harmonics x n^2 complex numbers): small
#: batches stay in cache and keep the peak memory low.
BATCH_BYTES = 2**20


@dataclass
class SpeedResponse:
    """Steady state at each input speed: ``q[i, j]`` is ``q_n`` for ``n = harmonics[j] >= 0``
    at ``speeds[i]`` (two-sided coefficients; ``q_{-n} = conj(q_n)``)."""

    speeds: np.ndarray
    harmonics: np.ndarray
    q: np.ndarray
    residual: np.ndarray
    success: np.ndarray


def lti_speeds(
    template: SpeedTemplate,
    speeds: Sequence[float] | np.ndarray,
    harmonics: Sequence[int] | None = None,
    *,
    loads: Callable[[np.ndarray, int], np.ndarray] | None = None,
    rtol: float = 1e-10,
) -> SpeedResponse:
    """Solve a time-invariant model at every input speed [rad/s] at once.

    Parameters
    ----------
    template
        ``model.speed_template()`` of a model whose coefficients have no harmonics.
    speeds
        Input speeds [rad/s], > 0.
    harmonics
        Harmonics ``n >= 0`` to solve (default: the model's load harmonics).
    loads
        ``loads(w1, n) -> f_n`` of shape ``(len(w1), n_dof)`` replacing the model's loads
        (e.g. an unbalance applied as a force); default: the model's.
    rtol
        A speed succeeds when its relative residual ``||f - A q|| / ||f||`` is below this.

    Examples
    --------
    >>> from rheolin.mechanics.model import Model
    >>> m = Model()
    >>> m.add_rigid_body("r", (0, 0, 0), 2.0, (0.1, 0.1, 0.2))
    >>> m.add_bearing("b", "r", 0, 8.0, 0.4, components=None)
    >>> m.add_force("f", "r", 0, force=(1.0, 0, 0), order=1)
    >>> out = lti_speeds(m.speed_template(), [1.0, 2.0])
    >>> out.harmonics, out.success
    (array([1]), array([ True,  True]))
    >>> x = out.q[:, 0, 0] * 2            # single-sided amplitude of ux at 1x
    >>> bool(np.allclose(x, 1 / (8.0 - 2.0 * np.array([1.0, 4.0]) + 0.4j * np.array([1, 2]))))
    True
    """
    if not template.time_invariant:
        raise ValueError(
            "lti_speeds needs a time-invariant model (no coefficient harmonics); use "
            "rheolin.results.sweep_speeds for time-varying ones"
        )
    speeds = np.asarray(speeds, dtype=float).ravel()
    if speeds.size == 0 or not np.all(np.isfinite(speeds)) or np.any(speeds <= 0):
        raise ValueError("`speeds` must be positive finite numbers [rad/s]")
    poly = template.mean_polynomials()
    f_poly = template.load_polynomials()
    loaded = [k for k, P in f_poly.items() if np.any(P != 0)]
    ns = np.array(sorted(loaded if harmonics is None else set(harmonics)), dtype=int)
    if ns.size == 0 or np.any(ns < 0):
        raise ValueError("`harmonics` must be integers >= 0 (and the model must be loaded)")
    w1 = float(template.plan.base) * speeds
    n = template.n_dof
    # A(w1, s) = sum_j c_j(w1, s) B_j over the nonzero X^(p) (X = K, D, M; weights 1, s, s^2)
    basis, powers = [], []
    for name, order in (("K", 0), ("D", 1), ("M", 2)):
        for p in range(3):
            if np.any(poly[name][p]):
                basis.append(poly[name][p].ravel())
                powers.append((order, p))
    B = np.array(basis, dtype=complex)  # (J, n^2)
    link = getattr(template, "constraint", None)
    Tc = None if link is None else link.transform().toarray()
    q = np.zeros((speeds.size, ns.size, n), dtype=complex)
    residual = np.zeros(speeds.size)
    weight = np.where(ns == 0, 1.0, 2.0)
    step = max(1, BATCH_BYTES // (16 * n * n * ns.size))
    for start in range(0, speeds.size, step):
        w = w1[start : start + step]
        sv = 1j * w[:, None] * ns[None, :]  # (speeds, harmonics)
        C = np.stack([sv**ws * (w**p)[:, None] for ws, p in powers], axis=-1)
        A = (C.reshape(-1, len(powers)) @ B).reshape(w.size, ns.size, n, n)
        if template.tables:  # speed-dependent bearings, evaluated at each speed
            for i, speed in enumerate(speeds[start : start + step]):
                for dofs, Kt, Dt, Mt in template.table_blocks(float(speed)):
                    idx = np.ix_(dofs, dofs)
                    for j, sj in enumerate(sv[i]):
                        A[i, j][idx] += Kt + sj * Dt + sj * sj * Mt
        F = np.stack([_load(f_poly, loads, w, int(k), n) for k in ns], axis=1)
        if Tc is not None:  # rigid links: eliminated (T^T A T y = T^T f, q = T y)
            A = np.einsum("ia,...ij,jb->...ab", Tc, A, Tc)
            F = F @ Tc
        with np.errstate(all="ignore"):
            Q = np.linalg.solve(A, F[..., None])[..., 0]
            R = F - (A @ Q[..., None])[..., 0]
        if Tc is not None:
            Q = Q @ Tc.T
        rn = np.sqrt(np.sum(weight * np.sum(np.abs(R) ** 2, axis=2), axis=1))
        fn = np.sqrt(np.sum(weight * np.sum(np.abs(F) ** 2, axis=2), axis=1))
        q[start : start + step] = Q
        residual[start : start + step] = np.where(fn > 0, rn / np.where(fn > 0, fn, 1.0), rn)
    success = np.isfinite(residual) & (residual <= max(rtol, 1e-12))
    return SpeedResponse(speeds, ns, q, residual, success)


def _load(
    f_poly: dict[int, np.ndarray],
    loads: Callable[[np.ndarray, int], np.ndarray] | None,
    w: np.ndarray,
    k: int,
    n: int,
) -> np.ndarray:
    if loads is not None:
        return np.asarray(loads(w, k), dtype=complex).reshape(w.size, n)
    P = f_poly.get(k)
    if P is None:
        return np.zeros((w.size, n), dtype=complex)
    return P[0][None] + w[:, None] * P[1][None] + (w * w)[:, None] * P[2][None]
