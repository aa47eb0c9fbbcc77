"""Half-power amplification factors and API 617 separation margins against the closed form
of an unbalanced single-degree-of-freedom rotor, ``x = e W^2 / |w_n^2 - W^2 + 2 i zeta w_n W|``
(peak, half-power speeds by root finding on the analytic curve)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from rheolin.results.api684 import amplification_factors, required_margin

WN = 120.0


def _x(W, zeta):  # type: ignore[no-untyped-def]
    return W**2 / np.abs(WN**2 - W**2 + 2j * zeta * WN * W)


def _reference(zeta):  # type: ignore[no-untyped-def]
    wp = WN / np.sqrt(1 - 2 * zeta**2)  # the peak of an unbalance (W^2-forced) response
    level = _x(wp, zeta) / np.sqrt(2)
    lo = brentq(lambda w: _x(w, zeta) - level, 0.2 * WN, wp)
    hi = brentq(lambda w: _x(w, zeta) - level, wp, 5 * WN)
    return wp, wp / (hi - lo)


@pytest.mark.parametrize("zeta", [0.02, 0.05, 0.1])
def test_sdof_amplification_factor_matches_the_closed_form(zeta):  # type: ignore[no-untyped-def]
    W = np.linspace(0.3 * WN, 3 * WN, 6001)
    (p,) = amplification_factors(W, _x(W, zeta))
    wp, af = _reference(zeta)
    assert p.speed == pytest.approx(wp, rel=1e-5)
    assert p.amplification_factor == pytest.approx(af, rel=2e-3)
    assert p.amplification_factor == pytest.approx(1 / (2 * zeta), rel=3 * zeta)


def test_two_resonances_margins_and_an_unresolved_peak():  # type: ignore[no-untyped-def]
    """Two rotors' responses summed (resonances at 120 and 300 rad/s), operating range
    150-240 rad/s: one peak below, one above, each with the API 617 requirement; a sweep that
    stops before the second peak's upper half-power point leaves its AF undetermined."""
    W = np.linspace(40.0, 500.0, 9001)
    amp = _x(W, 0.03) + 0.5 * (W / 300.0) ** 2 / np.abs(1 - (W / 300) ** 2 + 2j * 0.04 * W / 300)
    low, high = amplification_factors(W, amp, operating=(150.0, 240.0))
    assert low.speed == pytest.approx(WN, rel=5e-3) and high.speed == pytest.approx(300, rel=5e-3)
    assert low.margin == pytest.approx((150 - low.speed) / 150)
    assert high.margin == pytest.approx((high.speed - 240) / 240)
    af = low.amplification_factor
    assert low.required == pytest.approx(0.17 * (1 - 1 / (af - 1.5)))
    assert high.required == pytest.approx(0.10 + 0.17 * (1 - 1 / (high.amplification_factor - 1.5)))
    assert low.acceptable and high.acceptable  # 20 % and 25 % clear of the range
    cut = W < 303.0
    (_, partial) = amplification_factors(W[cut], amp[cut])
    assert partial.amplification_factor is None
    assert required_margin(2.4, True) == 0.0  # critically damped: no margin required
