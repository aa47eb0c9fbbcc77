"""A globalized Newton method for the static equilibrium ``r(y) = 0`` of a preloaded model.

The static residual of a model with Hertzian bearings and load-dependent meshes is the
gradient of its potential energy (the linear part's ``1/2 y^T K y - f^T y`` plus each
joint's convex potential), or close to one (cross-coupled or circulatory linear terms):
``r`` is monotone. Plain Newton fails on it where a joint has a clearance or a tangent
that vanishes at zero load: at ``y = 0`` no rolling element touches, the tangent is singular
along every radial direction, the residual is the same everywhere inside the clearance, and
a line search on ``|r|`` sees no descent. This method therefore

1. takes the Newton direction ``d = -(J + mu S)^-1 r`` (``S`` the reference stiffness of
   the linear part and of every joint: nonsingular once the free rigid-body motions are
   held), with ``mu = 0`` where ``J`` is regular and growing until ``d`` descends
   (``d^T r < 0``) and stays within a plausible deflection (a larger step comes from a
   nearly singular tangent, and its direction from round-off); when even the largest ``mu``
   leaves that range, the step of the largest ``mu`` is searched (a joint that carries
   almost nothing: the search reports it);
2. searches along ``d`` for the minimum of the energy, the root of the directional
   derivative ``g(a) = d^T r(y + a d)`` (nondecreasing for a monotone ``r``): the full
   Newton step when it reduces ``|W r|``, else a bracket grown by factors of 4 and
   narrowed by the Illinois method until ``|g| <= 0.1 |g(0)|``. The first step from rest
   thus crosses a clearance in one search ("start from first contact"), whatever its size;
3. stops when ``|W r|`` is at most the tolerance (``W``: rows scaled by ``1 / sqrt(S_ii)``,
   so forces and moments are comparable).

When ``g`` stays negative as the step grows past the allowed deflection, the load along
``d`` is not carried by anything: :class:`Unbounded` reports the direction, and the caller
names the joint and the load.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["MAX_ITERATIONS", "RTOL", "Outcome", "Unbounded", "minimize"]

#: Relative residual of a converged equilibrium (of the weighted load norm).
RTOL = 1e-10
#: Newton iterations before giving up (each has one factorization and a line search).
MAX_ITERATIONS = 200
#: Levenberg factors tried in turn when ``J`` is singular or its step does not descend.
_MU = (0.0, 1e-10, 1e-7, 1e-4, 1e-2, 1.0, 1e2, 1e4)
#: Line search: curvature condition ``|g(a)| <= _CURVATURE |g(0)|``, steps of the bracket.
_CURVATURE = 0.1
_SEARCH_STEPS = 80

Residual = Callable[[np.ndarray, bool], tuple[np.ndarray, Any]]


class Unbounded(Exception):
    """Along ``direction`` the energy keeps falling past the allowed deflection: nothing
    carries the load there."""

    def __init__(self, y: np.ndarray, direction: np.ndarray) -> None:
        super().__init__("the load is not carried along a direction")
        self.y = y
        self.direction = direction


@dataclass
class Outcome:
    """The end of :func:`minimize`."""

    y: np.ndarray
    converged: bool
    iterations: int
    residual: float  #: ``|W r|`` at ``y``
    tolerance: float


def _factor_solve(M: Any, r: np.ndarray) -> np.ndarray | None:
    try:
        with np.errstate(all="ignore"):
            d = -spla.splu(sp.csc_array(M)).solve(r)
    except RuntimeError:  # exactly singular
        return None
    return d if np.all(np.isfinite(d)) else None


def minimize(
    residual: Residual,
    y0: np.ndarray,
    S: sp.csc_array,
    weight: np.ndarray,
    scale: float,
    too_far: Callable[[np.ndarray], bool],
) -> Outcome:
    """Solve ``residual(y) = 0`` from ``y0`` (see the module).

    Parameters
    ----------
    residual
        ``residual(y, tangent) -> (r, J)`` (``J`` sparse, only when ``tangent``).
    S
        The reference stiffness (symmetric positive definite on the unknowns).
    weight, scale
        Rows of the residual norm ``|W r|`` and the load's norm ``|W f|``.
    too_far
        True for a ``y`` beyond any plausible equilibrium (the bracket stops there).
    """
    y = np.array(y0, dtype=float)
    r, J = residual(y, True)
    nr = float(np.linalg.norm(weight * r))
    eps = np.finfo(float).eps

    def tolerance(y: np.ndarray, J: Any) -> float:
        # the load's scale, or round-off of the internal forces of stiff parts (|J| |y|)
        noise = 1e3 * eps * float(np.linalg.norm(weight * (abs(sp.csc_array(J)) @ np.abs(y))))
        return max(RTOL * scale, noise)

    for it in range(1, MAX_ITERATIONS + 1):
        tol = tolerance(y, J)
        if nr <= tol:
            return Outcome(y, True, it - 1, nr, tol)
        step, steepest = None, None
        for mu in _MU:
            d = _factor_solve(J if mu == 0.0 else J + mu * S, r)
            if d is None or not float(d @ r) < 0.0:
                continue
            steepest = (mu, d)
            # a step past any plausible deflection comes from a (nearly) singular tangent:
            # its direction is round-off, so it is regularized further
            if not too_far(y + d):
                step = (mu, d)
                break
        if step is None:
            if steepest is None:
                return Outcome(y, False, it, nr, tol)
            # even the most regularized step leaves the plausible range: a load that (almost)
            # nothing carries; the search along it says whether the energy still falls there
            step = steepest
        mu, d = step
        y_new = _search(residual, y, r, nr, d, weight, newton=mu == 0.0, too_far=too_far)
        if y_new is None:
            return Outcome(y, False, it, nr, tol)
        r_new, J_new = residual(y_new, True)
        n_new = float(np.linalg.norm(weight * r_new))
        if np.array_equal(y_new, y):
            return Outcome(y, nr <= 10 * tol, it, nr, tol)
        y, r, J, nr = y_new, r_new, J_new, n_new
    tol = tolerance(y, J)
    return Outcome(y, nr <= tol, MAX_ITERATIONS, nr, tol)


def _search(
    residual: Residual,
    y: np.ndarray,
    r: np.ndarray,
    nr: float,
    d: np.ndarray,
    weight: np.ndarray,
    newton: bool,
    too_far: Callable[[np.ndarray], bool],
) -> np.ndarray | None:
    """The step along ``d``: the full Newton step when it reduces ``|W r|``, else the root of
    ``g(a) = d^T r(y + a d)`` to the curvature condition; None when ``d`` gains nothing."""

    def g(a: float) -> tuple[float, np.ndarray]:
        ra, _ = residual(y + a * d, False)
        return float(d @ ra), ra

    g0 = float(d @ r)
    g1, r1 = g(1.0)
    if newton and float(np.linalg.norm(weight * r1)) < (1 - 1e-4) * nr:
        return y + d
    a, ga, b, gb = 0.0, g0, 1.0, g1
    while gb < 0.0:  # the energy still falls at b: grow the bracket
        if too_far(y + b * d):
            raise Unbounded(y, d)
        a, ga = b, gb
        b *= 4.0
        gb, _ = g(b)
    side = 0
    c = b
    for _ in range(_SEARCH_STEPS):
        c = b - gb * (b - a) / (gb - ga) if gb != ga else 0.5 * (a + b)
        if not a < c < b:
            c = 0.5 * (a + b)
        gc, _ = g(c)
        if abs(gc) <= _CURVATURE * abs(g0):
            break
        if gc < 0.0:
            a, ga = c, gc
            if side == -1:
                gb *= 0.5  # Illinois: the stale end's value halved
            side = -1
        else:
            b, gb = c, gc
            if side == 1:
                ga *= 0.5
            side = 1
    return y + c * d if c > 0 else None
