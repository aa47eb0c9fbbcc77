"""Frequency response functions at a fixed speed against independent references.

* A rigid symmetric rotor on two isotropic bearings: the translation receptance at its disk is
  the single-mass closed form ``1 / (2k - m w^2 + 2 i c w)`` (gyroscopics act on the tilt only).
* A damped oscillator with a pumped stiffness ``k (1 + eps cos w1 t)`` forced by ``cos w t``
  at a frequency unrelated to ``w1``: the response and its sidebands ``w + h w1`` against a
  time integration (DOP853) fitted over a long window after the transient.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import rheolin as rl
from rheolin.errors import ModelError
from rheolin.results.frf import frequency_response, system_frequency_response

sys.path.insert(0, str(Path(__file__).parents[1] / "core"))
from cases import integrate


def _rigid_rotor(k: float, c: float) -> rl.Model:
    """A disk at the middle of a very stiff, nearly massless shaft on two bearings."""
    m = rl.Model()
    m.add_shaft("s", [0.0, 0.2, 0.4], outer_diameter=0.08, elastic_modulus=2.1e17,
                density=1e-6, poisson_ratio=0.3)  # fmt: skip
    m.add_disk("s", 1, mass=20.0, inertia=[0.2, 0.2, 0.4])
    for node in (0, 2):
        m.add_bearing(f"b{node}", "s", node, stiffness=k, damping=c)
    return m


def test_rigid_rotor_receptance_is_the_single_mass_closed_form() -> None:
    k, c, mass = 1e7, 400.0, 20.0
    model = _rigid_rotor(k, c)
    w = np.linspace(50.0, 2000.0, 40)
    frf = frequency_response(model, 300.0, w, inputs=["s:1:ux", "s:1:uy"])
    H = frf.receptance
    closed = 1.0 / (2 * k - mass * w**2 + 2j * c * w)
    # the shaft (E x 1e6, density 1e-6) adds a compliance of ~6e-8 of the bearings (x 25 at the
    # resonance, zeta = 0.02)
    assert np.max(np.abs(H[:, 0, 0] - closed) / np.abs(closed)) < 1e-5
    assert np.max(np.abs(H[:, 1, 1] - closed) / np.abs(closed)) < 1e-5
    assert np.max(np.abs(H[:, 1, 0])) < 1e-6 * np.max(np.abs(closed))  # isotropic: uncoupled
    assert frf.sidebands.tolist() == [0]  # time-invariant: no sidebands
    ds = frf.to_dataset()
    assert ds["receptance"].sel(output="s:1:ux", input="s:1:ux", part="imag").shape == (40,)


def _pumped(eps: float) -> rl.PeriodicSystem:
    """``q'' + 2 z wn q' + wn^2 (1 + eps cos w1 t) q = cos w t`` with ``w1 = 3``."""
    wn, z = 2.0, 0.1
    return rl.PeriodicSystem(
        3.0,
        M={0: np.eye(1)},
        D={0: 2 * z * wn * np.eye(1)},
        K={0: wn**2 * np.eye(1), 1: 0.5 * eps * wn**2 * np.eye(1)},
    )


def _fitted(system: rl.PeriodicSystem, w: float, hs: np.ndarray) -> np.ndarray:
    """Amplitudes ``q_h`` of ``Re sum_h q_h exp(i (w + h w1) t)`` from a time integration."""
    wn2, c = float(system.K[0][0, 0].real), float(system.D[0][0, 0].real)
    e = float(system.K[1][0, 0].real) * 2 / wn2
    w1 = system.omega

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        k = wn2 * (1 + e * np.cos(w1 * t))
        return np.array([y[1], np.cos(w * t) - c * y[1] - k * y[0]])

    t0, t1 = 120.0, 180.0  # the transient decays as exp(-0.4 t): 2e-21 by t0
    t = np.linspace(t0, t1, 6001)
    sol = integrate(rhs, (0.0, t1), [0.0, 0.0], t_eval=t, rtol=1e-12, atol=1e-14, method="DOP853")
    freqs = w + hs * w1
    # real basis: q(t) = sum_h a_h cos + b_h sin, q_h = a_h - i b_h
    basis = np.column_stack([np.cos(np.outer(t, freqs)), np.sin(np.outer(t, freqs))])
    coef, *_ = np.linalg.lstsq(basis, sol.y[0], rcond=None)
    return coef[: hs.size] - 1j * coef[hs.size :]


@pytest.mark.parametrize("w", [1.3, 2.05, 4.7])
def test_pumped_oscillator_response_and_sidebands_against_time_integration(w: float) -> None:
    system = _pumped(0.4)
    frf = system_frequency_response(system, [w], inputs=[0], order=8)
    hs = np.arange(-3, 4)
    ref = _fitted(system, w, np.arange(-8, 9))[5:12]  # fitted with the small outer sidebands
    got = np.array([frf.response[0, int(np.flatnonzero(frf.sidebands == h)[0]), 0, 0] for h in hs])
    scale = np.abs(ref).max()
    assert np.max(np.abs(got - ref)) < 1e-9 * scale, (got, ref)
    assert abs(frf.receptance[0, 0, 0] - ref[3]) < 1e-9 * scale
    assert np.abs(ref[4]) > 1e-2 * scale  # the sidebands are really there
    assert frf.info["boundary_fraction"] < 1e-12


def test_coarse_lattice_warns_that_sidebands_are_truncated() -> None:
    from rheolin.harmonics import TruncationWarning

    with pytest.warns(TruncationWarning, match="outer shell"):
        system_frequency_response(_pumped(1.5), [2.0], inputs=[0], order=1)


def test_bad_dofs_and_frequencies_are_named() -> None:
    model = _rigid_rotor(1e7, 100.0)
    with pytest.raises(ModelError, match="body:node:component"):
        frequency_response(model, 100.0, [10.0], inputs=["s:1"])
    with pytest.raises(ModelError, match="no body 'x'"):
        frequency_response(model, 100.0, [10.0], inputs=["x:1:ux"])
    with pytest.raises(ModelError, match="has no node 7"):
        frequency_response(model, 100.0, [10.0], inputs=["s:7:ux"])
    with pytest.raises(ModelError, match="component must be one of"):
        frequency_response(model, 100.0, [10.0], inputs=["s:1:rx"])
    with pytest.raises(ModelError, match="frequencies"):
        frequency_response(model, 100.0, [-1.0], inputs=["s:1:ux"])


def test_undamped_resonance_is_reported_singular_not_a_number() -> None:
    """At the natural frequency of an undamped oscillator ``Q(i w)`` is singular: NaN there
    and the frequency listed, the closed form ``1 / (k - w^2)`` elsewhere."""
    s = rl.PeriodicSystem(1.0, M={0: np.eye(1)}, K={0: 4.0 * np.eye(1)})
    frf = system_frequency_response(s, [1.0, 2.0, 3.0], inputs=[0])
    H = frf.receptance[:, 0, 0]
    assert frf.info["singular"] == [2.0] and np.isnan(H[1])
    assert H[0] == pytest.approx(1 / 3) and H[2] == pytest.approx(-1 / 5)
