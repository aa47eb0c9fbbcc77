"""``transient``: the time-domain baseline (BDF from rest until the steady state is periodic).

The seed's baseline, shipped so that a frequency-domain result can be cross-checked and so
that the speed-up can be measured on the same model. ``M(t) q'' + D(t) q' + K(t) q = f(t)``
is integrated from rest in first-order form ``y = (q, v)``:

* backend ``"scipy"``: :class:`scipy.integrate.BDF` on ``y' = (v, M(t)^-1 (f - D v - K q))``.
  ``M_0`` is factorized once (sparse LU); a time-varying mass ``M(t) = M_0 + dM(t)`` whose
  support is small (rotating rigid nodes) is inverted by the Woodbury identity on that
  support, else ``M(t)`` is factorized per call. The Jacobian
  ``[[0, I], [-M^-1 K, -M^-1 D]]`` is dense or sparse by its fill.
* backend ``"sundae"`` (optional, when ``scikit-sundae`` is importable): SUNDIALS IDA (BDF)
  on the implicit residual ``(q' - v, M(t) v' + D(t) v + K(t) q - f(t))``, which keeps the
  mass matrix as it is and takes the exact sparse Jacobian ``dF/dy + c_j dF/dy'`` (no
  ``M^-1``).

Coefficients are evaluated as ``X(t) = X_0 + sum_{k>0} 2 Re(X_k) cos(k w1 t) - 2 Im(X_k)
sin(k w1 t)`` on a fixed sparse pattern of the time-varying part only.

Steady-state detection. The response repeats with the period ``P = 2 pi / (g w1)``, ``g`` the
greatest common divisor of the system's coefficient and load harmonics (the shortest period
that actually repeats, often much shorter than ``2 pi / w1``). ``q`` is sampled ``S`` times per
period (``S > 2 max|n| / g`` so no harmonic of ``H`` aliases onto another); integration stops
when the relative change between two consecutive periods, ``max|q_p - q_{p-1}| / max|q_p|``, is
below ``period_tol`` (default ``max(1e-6, 10 rtol)``), or fails (``status=1``) at
``max_periods``, or earlier when the change has stalled at the integrator's own noise (no
decrease over ``STALL_WINDOW`` periods while below ``STALL_NOISE * rtol``: ``period_tol`` is
below what ``rtol`` resolves, and more periods would not help). The harmonics are the DFT of
the last period at the indices of ``H``.

Cost, honestly: a hunting-tooth gearbox repeats only after thousands of shaft revolutions,
and the detector needs at least two such periods, each resolved at the mesh frequency: that is
the baseline's cost, and the reason for the frequency domain.
"""

from __future__ import annotations

import logging

import numpy as np

from ...harmonics.balance import HarmonicBalance
from ..registry import Options, SolverOutcome, register
from .backends import run_scipy, run_sundae
from .model import Coefficients, Detector, SingularMass
from .settings import STALL_WINDOW, TransientSettings

__all__ = ["solve_transient"]

log = logging.getLogger(__name__)


@register("transient", residual_checked=False)
def solve_transient(op: HarmonicBalance, opts: Options) -> SolverOutcome:
    """Integrate from rest with BDF until the response is periodic; harmonics of the last period.

    Options (``rl.solve(..., method="transient", options={...})``, defaults in
    :data:`~rheolin.solvers.transient.settings.DEFAULTS`): ``rtol``, ``atol`` (integrator
    tolerances), ``period_tol`` (relative change between consecutive periods that counts as
    steady), ``max_periods`` (cap; ``maxiter`` sets it too), ``samples`` (per period),
    ``period`` (comparison window, a multiple of the shortest repeating period),
    ``max_step``, ``backend`` (``"scipy"``, ``"sundae"`` or ``"auto"``).

    ``iterations`` is the number of integrated periods; ``history`` the relative change per
    period; ``info`` holds ``periods``, ``steps``, ``period`` [s], ``samples``, ``backend``.
    ``success`` is judged by the detector, not by the harmonic-balance residual (the
    integrated response also holds harmonics outside ``H``).

    Examples
    --------
    >>> import numpy as np, rheolin as rl
    >>> s = rl.PeriodicSystem(1.0, M={0: np.eye(1)}, D={0: 0.5 * np.eye(1)},
    ...                       K={0: 4 * np.eye(1), 1: 0.5 * np.eye(1)}, f={1: np.ones(1)})
    >>> sol = rl.solve(s, 6, method="transient", options={"backend": "scipy"})
    >>> ref = rl.solve(s, 6, method="direct")
    >>> sol.success, bool(abs(sol.harmonic(1) - ref.harmonic(1)).max() < 1e-6)
    (True, True)
    """
    with np.errstate(under="ignore"):
        s = TransientSettings.from_options(op, opts)
        det = Detector(s, op.n_dof, opts.callback)
        try:
            c = Coefficients(op.system)
            stats = (run_sundae if s.backend == "sundae" else run_scipy)(c, s, det)
        except SingularMass as exc:
            return SolverOutcome(
                np.zeros((op.pos.size, op.n_dof), dtype=complex),
                False,
                3,
                f"the mass matrix is singular ({exc}): the transient method needs a "
                "nonsingular M(t) (massless DOFs make the system algebraic)",
                "transient",
            )
        Q = det.harmonics(op)
    info = {
        "periods": det.periods,
        "steps": stats["steps"],
        "period": s.period,
        "samples": s.samples,
        "backend": s.backend,
        **{k: v for k, v in stats.items() if k not in ("steps", "failed")},
    }
    last = det.history[-1] if det.history else float("nan")
    where = f"{det.periods} periods of {s.period:.6g} s, {stats['steps']} steps, {s.backend}"
    if "failed" in stats:
        return SolverOutcome(
            Q,
            False,
            3,
            f"transient: {stats['failed']} ({where})",
            "transient",
            det.periods,
            det.history,
            info,
        )
    if det.stalled:
        return SolverOutcome(
            Q,
            False,
            1,
            f"transient: the change between periods stalled at {last:.3g} over the last "
            f"{STALL_WINDOW} periods, above period_tol={s.period_tol:g} ({where}). That is the "
            f"integrator's noise at rtol={s.rtol:g}: lower `rtol` or raise `period_tol` "
            "(the harmonics of the last period are returned)",
            "transient",
            det.periods,
            det.history,
            info,
        )
    if det.done:
        return SolverOutcome(
            Q,
            True,
            0,
            f"periodic steady state after {where}: change between the last two periods "
            f"{last:.3g} <= period_tol={s.period_tol:g}",
            "transient",
            det.periods,
            det.history,
            info,
        )
    return SolverOutcome(
        Q,
        False,
        1,
        f"transient: no periodic steady state within the cap of max_periods={s.max_periods} "
        f"periods ({where}); the change between the last two periods is {last:.3g} > "
        f"period_tol={s.period_tol:g}. The system may be undamped, resonant or unstable, or "
        "decay slowly: raise `max_periods` or check its stability",
        "transient",
        det.periods,
        det.history,
        info,
    )
