"""Gear meshes against independent references: Mathieu bands (scipy.special), exact quadrature
of the rectangular stiffness wave, and the rigid-body kinematics of the contact point."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation
from scipy.special import mathieu_a, mathieu_b

import rheolin as rl
from rheolin.errors import ModelError
from rheolin.mechanics.gears import (
    gear_mesh_term,
    line_of_action,
    mesh_convolve,
    rectangular_wave_coefficients,
)
from rheolin.mechanics.speeds import GearPair, speed_plan

J1, J2, RB1, RB2, K0, ALPHA = 0.01, 0.04, 0.05, 0.10, 1e8, np.radians(20)
OMEGA0 = np.sqrt(K0 * (RB1**2 / J1 + RB2**2 / J2))  # natural frequency of delta = w^T q


def _torsional_pair_system(a: float, eps: float):
    """Pinion (20 teeth) and gear (40 teeth), bearings rigid: torsional DOFs only.

    ``delta'' + Omega0^2 (1 + eps cos W_m t) delta = 0`` is Mathieu's equation with
    ``tau = W_m t / 2``, ``a = 4 Omega0^2 / W_m^2``, ``q = -a eps / 2``.
    """
    plan = speed_plan("pinion", [GearPair("pinion", "gear", 20, 40)])
    mesh = plan.mesh[0]  # mesh harmonic in units of w1
    W_mesh = 2 * OMEGA0 / np.sqrt(a)
    w1 = W_mesh / mesh
    centre = (RB1 + RB2) / np.cos(ALPHA)
    w = line_of_action([0, 0, 0], [centre, 0, 0], [0, 0, 1], RB1, RB2, ALPHA)
    term = gear_mesh_term(range(6), range(6, 12), w, mesh, {0: K0, 1: K0 * eps / 2})
    keep = [5, 11]  # phiz of pinion and gear; translations held by rigid bearings
    K = {k: v[np.ix_(keep, keep)] for k, v in term.K.items()}
    system = rl.PeriodicSystem(omega=w1, M={0: np.diag([J1, J2])}, K=K)
    return system, mesh, W_mesh


def _mathieu_unstable(a: float, q: float, m: int) -> bool:
    return bool(mathieu_b(m, abs(q)) < a < mathieu_a(m, abs(q)))


def _band_edges(m: int, eps: float) -> tuple[float, float]:
    """Solve a = b_m(a eps/2) and a = a_m(a eps/2) (q depends on a along a speed sweep)."""
    lo = brentq(lambda a: a - mathieu_b(m, a * eps / 2), 0.5 * m * m, 1.5 * m * m)
    hi = brentq(lambda a: a - mathieu_a(m, a * eps / 2), 0.5 * m * m, 1.5 * m * m)
    return lo, hi


@pytest.mark.parametrize("eps", [0.1, 0.25, 0.5])
@pytest.mark.parametrize("m", [1, 2])
def test_mesh_stiffness_variation_gives_mathieu_bands(m, eps):
    lo, hi = _band_edges(m, eps)
    width = hi - lo
    for frac in (-0.1, 0.1, 0.9, 1.1):  # just outside, just inside, inside, just outside
        a = lo + frac * width
        expected = _mathieu_unstable(a, a * eps / 2, m)
        assert expected == (0 < frac < 1)
        system, mesh, W_mesh = _torsional_pair_system(a, eps)
        res = rl.floquet(system, rl.HarmonicSet(mesh * np.arange(0, 16)))
        # the rigid-body rotation mode gives an exponent 0 (up to round-off)
        unstable = res.max_real > 1e-6 * W_mesh
        assert unstable == expected, (m, eps, frac, res.max_real / W_mesh)


def test_rectangular_wave_coefficients_against_quadrature():
    ratio, ks, kd, phase = 1.63, 3.0e8, 5.2e8, 0.7
    coeffs = rectangular_wave_coefficients(ratio, ks, kd, 12, phase=phase)
    half = np.pi * (ratio - 1.0)  # half width of the double-contact interval [mesh rad]

    def k_of(theta: float) -> float:
        dist = (theta - phase + np.pi) % (2 * np.pi) - np.pi
        return kd if abs(dist) < half else ks

    breaks = [phase - half, phase + half]
    for j in range(-12, 13):
        lo, hi = -np.pi + phase, np.pi + phase
        re = quad(lambda t, j=j: k_of(t) * np.cos(j * t), lo, hi, points=breaks)[0]
        im = quad(lambda t, j=j: -k_of(t) * np.sin(j * t), lo, hi, points=breaks)[0]
        ref = (re + 1j * im) / (2 * np.pi)
        assert abs(coeffs[j] - ref) < 1e-9 * kd, j
    with pytest.raises(ModelError, match="contact_ratio"):
        rectangular_wave_coefficients(2.5, ks, kd, 3)


def test_transmission_error_load_is_k_times_e_in_time():
    k = {0: 2.0e8, 1: 0.3e8 - 0.1e8j, 2: 0.05e8}
    e = {0: 1e-6, 1: 2e-6j, 3: 0.5e-6}
    w = np.linspace(-1, 1, 12)
    mesh = 7
    term = gear_mesh_term(range(6), range(6, 12), w, mesh, k, transmission_error=e)
    for t in np.linspace(0, 2 * np.pi, 9):
        kt = sum(
            (c * np.exp(1j * j * t) + (np.conj(c) * np.exp(-1j * j * t) if j else 0)).real
            for j, c in k.items()
        )
        et = sum(
            (c * np.exp(1j * j * t) + (np.conj(c) * np.exp(-1j * j * t) if j else 0)).real
            for j, c in e.items()
        )
        ft = sum(v * np.exp(1j * n * t / mesh) for n, v in term.f.items())
        scale = 2e8 * 3e-6  # |k| |e|
        assert np.allclose(ft.imag, 0, atol=1e-12 * scale)
        assert np.allclose(ft.real, kt * et * w, rtol=0, atol=1e-12 * scale)
    assert set(mesh_convolve({0: 1, 1: 1, -1: 1}, {2: 1, -2: 1})) == {-3, -2, -1, 1, 2, 3}


@pytest.mark.parametrize("helix", [0.0, np.radians(15), -np.radians(25)])
@pytest.mark.parametrize("side", [1, -1])
def test_line_of_action_matches_contact_point_kinematics(helix, side):
    """delta = n . (motion of the contact point on the pinion - on the gear), exact rotations."""
    xa, xb, axis = np.array([0.1, 0.2, 0.3]), None, np.array([1.0, 2.0, 2.0]) / 3
    ex = np.cross(axis, [0, 0, 1.0])
    ex /= np.linalg.norm(ex)
    xb = xa + ex * (RB1 + RB2) / np.cos(ALPHA) + 0.02 * axis
    w = line_of_action(xa, xb, axis, RB1, RB2, ALPHA, helix_angle=helix, side=side)
    n = w[:3]
    assert np.isclose(np.linalg.norm(n), 1.0)
    assert np.isclose(abs(n @ axis), abs(np.sin(np.arctan(np.tan(helix) * np.cos(ALPHA)))))
    # torsional lever arms are the base radii times cos(beta_b)
    cb = np.cos(np.arctan(np.tan(helix) * np.cos(ALPHA)))
    assert np.isclose(w[3:6] @ axis, side * RB1 * cb)
    assert np.isclose(w[9:12] @ axis, side * RB2 * cb)
    P = xa + ex * RB1 / np.cos(ALPHA)
    rng = np.random.default_rng(1)
    q = rng.standard_normal(12) * 1e-7

    def moved(x, u, phi):
        return x + u + Rotation.from_rotvec(phi).apply(P - x)

    delta = n @ (moved(xa, q[:3], q[3:6]) - moved(xb, q[6:9], q[9:12]))
    assert np.isclose(delta, w @ q, rtol=1e-6, atol=0)
