"""The stability map at standstill and over wide speed steps, against closed forms.

A rigid rotor (mass 1, inertias 1) on a spring fixed in its own axes (``k_x = 1e4``,
``k_y = 1.21e4``, damping ``c_x = 2``, ``c_y = 1``) and an isotropic support on the other
components (stiffness 1e4, damping 10). At standstill the spring stays where ``t = 0`` put it:
the exponents are those of two independent oscillators, ``-c/2 +- i sqrt(k - c^2/4)``, not
those of the time-averaged (isotropic, ``(k_x + k_y) / 2``) spring. Spinning without its
damping, the rotor is unstable exactly between its two natural frequencies, 100 and 110 rad/s.
"""

from __future__ import annotations

import numpy as np
import pytest

from rheolin.mechanics import Model
from rheolin.stability import stability_map
from rheolin.stability.standstill import STANDSTILL, standstill_verdict


def _rotor(damped: bool = True) -> Model:
    m = Model()
    m.add_rigid_body("r", (0, 0, 0), 1.0, (1.0, 1.0, 1.0))
    damping = [2.0, 1.0] if damped else 0.0
    m.add_bearing("s", "r", 0, [1e4, 1.21e4], damping, components=("ux", "uy"), frame="r")
    m.add_bearing("g", "r", 0, 1e4, 10.0, components=("uz", "phix", "phiy", "phiz"))
    return m


def _oscillator(k: float, c: float) -> list[complex]:
    root = np.sqrt(k - c * c / 4)
    return [complex(-c / 2, root), complex(-c / 2, -root)]


def _sorted(z: np.ndarray) -> np.ndarray:
    """By frequency, then damping (rounded: equal values differ in their last digits)."""
    return np.array(sorted(z, key=lambda x: (round(x.imag, 6), round(x.real, 6))))


def test_standstill_is_the_frozen_system_not_the_averaged_one() -> None:
    """The exponents at standstill, searched or certified by their (zero-radius) discs, are
    the closed-form oscillators' (1e-9 relative); the map's standstill point says what it
    did."""
    res = standstill_verdict(_rotor(), STANDSTILL)
    truth = _oscillator(1e4, 2.0) + _oscillator(1.21e4, 1.0) + 4 * _oscillator(1e4, 10.0)
    skipped = np.asarray(res.info["certified_modes"])
    pairs = skipped[skipped.imag > 0]
    got = _sorted(np.concatenate([res.exponents, skipped, pairs.conj()]))
    assert got.size == len(truth)
    np.testing.assert_allclose(got, _sorted(np.array(truth)), rtol=1e-9)
    smap = stability_map(_rotor(), np.array([0.0]))
    assert smap.state.tolist() == ["stable"]
    assert smap.max_real[0] == pytest.approx(-0.5, rel=1e-9)
    assert smap.frequency[0] == pytest.approx(np.sqrt(1.21e4 - 0.25), rel=1e-9)
    assert "frozen at t = 0" in smap.info["standstill"]
    assert "frozen at t = 0" in res.info["note"]


def test_wide_steps_start_cold_and_keep_the_closed_form_verdicts() -> None:
    """Speeds 1 % apart continue, 8 % and more start cold; every verdict is the closed
    form's (unstable inside 100..110 rad/s, stable outside)."""
    speeds = np.array([95.0, 96.0, 105.0, 106.0, 130.0])
    smap = stability_map(_rotor(damped=False), speeds, refine=0, identify_mechanism=False)
    assert smap.info["continued"] == 2
    inside = (speeds > 100) & (speeds < 110)
    assert smap.state.tolist() == ["unstable" if x else "stable" for x in inside]
