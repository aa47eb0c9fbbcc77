"""Settings of the transient method: the validated options of one run and the thresholds.

The bottom of the transient package: the time-domain model (:mod:`.model`) and the integrator
backends (:mod:`.backends`) import only this module, and :mod:`.method` imports all three.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import reduce
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...system.periodic import PeriodicSystem

if TYPE_CHECKING:
    from ...harmonics.balance import HarmonicBalance
    from ..registry import Options

__all__ = [
    "DEFAULTS",
    "DENSE_JAC_MAX",
    "DENSE_MAX",
    "STALL_NOISE",
    "STALL_RATIO",
    "STALL_WINDOW",
    "WOODBURY_MAX",
    "TransientSettings",
    "repeat_divisor",
    "sundae_available",
]

#: Default method options (``rl.solve(..., method="transient", options={...})``).
DEFAULTS: dict[str, Any] = {
    "rtol": 1e-8,  # integrator relative tolerance
    "atol": None,  # absolute tolerance; None: rtol * response scale (q and v apart)
    "period_tol": None,  # period-to-period change that ends the run; None: max(1e-6, 10 rtol)
    "max_periods": 1000,  # cap on integrated periods (``maxiter`` also sets it)
    "samples": None,  # samples per period; None: 4 max(|n|, |k|) / g + 4
    "period": None,  # comparison window [s]; a multiple of the shortest repeating period
    "max_step": None,  # None: half the period of the highest harmonic of H and the system
    "backend": "auto",  # "scipy", "sundae" or "auto" (sundae when importable)
}

#: Woodbury for ``M(t)^-1`` up to this many DOFs of time-varying mass; above, LU per call.
WOODBURY_MAX = 256
#: Dense Jacobian for the SciPy backend when ``2 n`` is at most this, or when it is filled.
DENSE_JAC_MAX = 800
#: Dense mean matrices (and an explicit ``M_0^-1``) up to this many DOFs.
DENSE_MAX = 300
#: The change between periods has stalled when, over this many periods, it fell by less than
#: ``STALL_RATIO`` per period (geometric mean) while below ``STALL_NOISE * rtol``.
STALL_WINDOW = 6
STALL_RATIO = 0.95
STALL_NOISE = 100.0


def sundae_available() -> bool:
    """True when the optional SUNDIALS backend (``scikit-sundae``) can be imported."""
    try:
        import sksundae.ida  # noqa: F401
    except ImportError:
        return False
    return True


@dataclass
class TransientSettings:
    """Validated options of one run (see :data:`DEFAULTS`)."""

    rtol: float
    atol: float | np.ndarray
    period_tol: float
    max_periods: int
    samples: int
    period: float
    divisor: float  # harmonic n sits at DFT bin n / divisor
    max_step: float
    backend: str

    @classmethod
    def from_options(cls, op: HarmonicBalance, opts: Options) -> TransientSettings:
        """Merge ``opts.extra`` over :data:`DEFAULTS`, validate, derive the sampling."""
        extra = dict(opts.extra)
        unknown = sorted(set(extra) - set(DEFAULTS))
        if unknown:
            raise ValueError(f"unknown transient option(s) {unknown}; allowed: {sorted(DEFAULTS)}")
        o = {**DEFAULTS, **extra}
        if "max_periods" not in extra and opts.maxiter is not None:
            o["max_periods"] = int(opts.maxiter)
        rtol = _positive(o["rtol"], "rtol")
        period_tol = (
            max(1e-6, 10 * rtol)
            if o["period_tol"] is None
            else _positive(o["period_tol"], "period_tol")
        )
        max_periods = o["max_periods"]
        if isinstance(max_periods, bool) or not isinstance(max_periods, int) or max_periods < 2:
            raise ValueError(f"`max_periods` must be an integer >= 2, got {max_periods!r}")
        backend = o["backend"]
        if backend not in ("auto", "scipy", "sundae"):
            raise ValueError(f"`backend` must be 'auto', 'scipy' or 'sundae', got {backend!r}")
        if backend == "auto":
            backend = "sundae" if sundae_available() else "scipy"
        elif backend == "sundae" and not sundae_available():
            raise ValueError(
                "`backend`='sundae' needs the optional package scikit-sundae "
                "(pip install scikit-sundae); use 'scipy'"
            )
        system = op.system
        g = repeat_divisor(system)
        T = 2 * math.pi / system.omega
        divisor = float(g)
        if o["period"] is not None:
            P = _positive(o["period"], "period")
            ratio = P / (T / g)
            if abs(ratio - round(ratio)) > 1e-9 * ratio or round(ratio) < 1:
                raise ValueError(
                    f"`period` must be a positive integer multiple of the shortest repeating "
                    f"period {T / g:.9g} s (2 pi / ({g} w1)), got {P!r}"
                )
            divisor = g / round(ratio)
        period = 2 * math.pi / (divisor * system.omega)
        top = max(
            [abs(int(n)) for n in op.full]
            + [abs(k) for k in system.coefficient_harmonics]
            + [abs(k) for k in system.load_harmonics]
        )
        need = math.floor(2 * max(abs(int(n)) for n in op.full) / divisor) + 1
        samples = o["samples"]
        if samples is None:
            samples = max(math.ceil(4 * max(top, 1) / divisor) + 4, 16)
        elif isinstance(samples, bool) or not isinstance(samples, int) or samples < need:
            raise ValueError(
                f"`samples` must be an integer >= {need} (2 max|n| / g + 1 for this harmonic "
                f"set, else harmonics alias), got {samples!r}"
            )
        max_step = o["max_step"]
        if max_step is None:
            max_step = 0.5 * 2 * math.pi / (system.omega * max(top, 1))
        max_step = _positive(max_step, "max_step")
        atol = _default_atol(op, rtol) if o["atol"] is None else _positive(o["atol"], "atol")
        return cls(rtol, atol, period_tol, max_periods, samples, period, divisor, max_step, backend)


def repeat_divisor(system: PeriodicSystem) -> int:
    """``g``: the greatest common divisor of the coefficient and load harmonics (>= 1).

    The steady state contains only multiples of ``g``, so it repeats every ``2 pi / (g w1)``.

    >>> import numpy as np
    >>> s = PeriodicSystem(1.0, M={0: np.eye(1)}, K={0: np.eye(1), 4: np.eye(1)},
    ...                    f={2: np.ones(1)})
    >>> repeat_divisor(s)
    2
    """
    ks = [abs(k) for k in (*system.coefficient_harmonics, *system.load_harmonics) if k]
    return int(reduce(math.gcd, ks, 0)) or 1


def _positive(x: Any, name: str) -> float:
    try:
        v = float(x)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be a positive number, got {x!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"`{name}` must be a positive finite number, got {x!r}")
    return v


def _default_atol(op: HarmonicBalance, rtol: float) -> np.ndarray:
    """``rtol`` times the size of the steady response (q and v separately).

    The error allowed on every DOF is then ``rtol`` of the largest response, which is the
    accuracy asked of the dominant harmonics; a tighter floor makes the integrator resolve
    the quiet DOFs to round-off, in more steps and with a change between periods that
    stalls above ``period_tol``.

    Solves ``A0(n) q_n = f_n`` for the load harmonics only (a few sparse LUs); falls back to
    ``|f| / |K_0|`` when a block is singular (an undamped resonance).
    """
    s = op.system
    n = s.n
    q_scale = v_scale = 0.0
    try:
        for k in s.load_harmonics:
            if k < 0:
                continue
            A = op.A0_matrix(k)
            rhs = s.load(k) if k else s.load(k).real
            with np.errstate(all="ignore"):
                q = (
                    spla.spsolve(sp.csc_array(A), rhs)
                    if sp.issparse(A)
                    else np.linalg.solve(A, rhs)
                )
            amp = float(np.max(np.abs(q)))
            if not np.isfinite(amp):
                raise np.linalg.LinAlgError
            q_scale += amp * (1.0 if k == 0 else 2.0)
            v_scale += amp * 2.0 * k * s.omega
    except (RuntimeError, np.linalg.LinAlgError, ValueError, FloatingPointError):
        q_scale = v_scale = 0.0
    if not (q_scale > 0 and np.isfinite(q_scale)):
        f_max = max(float(np.max(np.abs(v))) for v in s.f.values()) if s.f else 1.0
        k0 = s.K.get(0)
        k_max = float(np.max(np.abs(k0.data if sp.issparse(k0) else k0))) if k0 is not None else 1.0
        q_scale = f_max / k_max
        top = max((abs(k) for k in s.load_harmonics), default=1) or 1
        v_scale = q_scale * top * s.omega
    v_scale = max(v_scale, q_scale * s.omega)
    return np.concatenate([np.full(n, rtol * q_scale), np.full(n, rtol * v_scale)])
