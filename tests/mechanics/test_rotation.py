"""Exact Fourier coefficients of rotating body-frame quantities vs sampling and closed forms."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
import scipy.linalg as sla

import rheolin as rl
from rheolin.errors import ModelError
from rheolin.mechanics.rotation import (
    circulatory_matrix,
    rotate_body_matrix,
    rotate_body_vector,
    rotation_series,
    skew,
)

AXIS = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])


def _samples(series, w1, t):
    return sum(
        v[None] * np.exp(1j * k * w1 * t)[(...,) + (None,) * v.ndim] for k, v in series.items()
    ).real


def _fft_coefficients(values, n_samples):
    """Two-sided Fourier coefficients of samples over one period (axis 0)."""
    c = np.fft.fft(values, axis=0) / n_samples
    return {k: c[k % n_samples] for k in range(-n_samples // 2 + 1, n_samples // 2)}


def test_rotation_series_is_the_matrix_exponential():
    w1, s = 3.0, -2
    R = rotation_series(AXIS, s)
    for t in np.linspace(0.0, 1.3, 7):
        exact = sla.expm(s * w1 * t * skew(AXIS))
        np.testing.assert_allclose(_samples(R, w1, np.array([t]))[0], exact, atol=1e-14)


@pytest.mark.parametrize("s", [1, 3, -2])
def test_rotate_body_matrix_matches_sampled_fft(s):
    rng = np.random.default_rng(4)
    X = rng.standard_normal((12, 12))  # any matrix over four 3-blocks, not symmetric
    w1, n = 1.7, 32
    t = np.arange(n) * 2 * np.pi / (w1 * n)
    samples = []
    for ti in t:
        Rt = np.kron(np.eye(4), sla.expm(s * w1 * ti * skew(AXIS)))
        samples.append(Rt @ X @ Rt.T)
    ref = _fft_coefficients(np.array(samples), n)
    got = rotate_body_matrix(X, AXIS, s)
    assert set(got) == {0, s, -s, 2 * s, -2 * s}
    for k, v in ref.items():
        np.testing.assert_allclose(got.get(k, 0.0), v, atol=1e-12)
    assert got[0].dtype == float


def test_circulatory_matrix_matches_sampled_fft():
    rng = np.random.default_rng(5)
    X = rng.standard_normal((6, 6))
    w1, s, n = 2.5, 2, 32
    W = s * w1
    t = np.arange(n) * 2 * np.pi / (w1 * n)
    samples = []
    for ti in t:
        R = sla.expm(W * ti * skew(AXIS))
        Rt, dRt = np.kron(np.eye(2), R), np.kron(np.eye(2), W * skew(AXIS) @ R)
        samples.append(Rt @ X @ dRt.T)
    ref = _fft_coefficients(np.array(samples), n)
    got = circulatory_matrix(X, AXIS, s, w1)
    for k, v in ref.items():
        np.testing.assert_allclose(got.get(k, 0.0), v, atol=1e-11)


def test_isotropic_rotating_damping_circulatory_closed_form():
    c_r, W = 3.0, 40.0
    D_B = c_r * (np.eye(3) - np.outer(AXIS, AXIS))  # isotropic in the plane normal to the axis
    Kc = circulatory_matrix(D_B, AXIS, 1, W)
    assert sorted(Kc) == [0]
    # in axes (a, b, e) with b = e x a: c_r W [[0, 1], [-1, 0]]
    a = np.cross(AXIS, [1.0, 0, 0])
    a /= np.linalg.norm(a)
    b = np.cross(AXIS, a)
    Q = np.array([a, b, AXIS])
    np.testing.assert_allclose(
        Q @ Kc[0] @ Q.T, c_r * W * np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 0]]), atol=1e-12
    )


def test_rotating_damping_instability_threshold():
    # Jeffcott rotor, rotating damping c_r, stationary c_n: unstable above w_n (1 + c_n / c_r)
    m, k, c_r, c_n = 2.0, 8.0e4, 6.0, 3.0
    wn = np.sqrt(k / m)
    e = np.array([0.0, 0.0, 1.0])
    K_B = np.diag([k, k, 5 * k])
    D_B = np.diag([c_r, c_r, 0.0])

    def max_real(W):
        K = rotate_body_matrix(K_B, e, 1)[0] + circulatory_matrix(D_B, e, 1, W)[0]
        D = rotate_body_matrix(D_B, e, 1)[0] + c_n * np.diag([1.0, 1.0, 1.0])
        A = np.block([[np.zeros((3, 3)), np.eye(3)], [-K / m, -D / m]])
        return np.linalg.eigvals(A).real.max()

    w_th = wn * (1 + c_n / c_r)
    assert max_real(0.98 * w_th) < 0 < max_real(1.02 * w_th)


def test_asymmetric_jeffcott_unbalance_response_closed_form():
    # docs/solvers.md, reference cases: z = x + i y = P exp(i W t) exactly
    m, kx, ky, c, ecc, beta, W = 1.5, 6e4, 4e4, 20.0, 1e-4, 0.7, 150.0
    e = np.array([0.0, 0.0, 1.0])
    K = rotate_body_matrix(np.diag([kx, ky, 1e5]), e, 1)
    f = rotate_body_vector(m * ecc * W**2 * np.array([np.cos(beta), np.sin(beta), 0.0]), e, 1)
    system = rl.PeriodicSystem(omega=W, M={0: m * np.eye(3)}, D={0: c * np.eye(3)}, K=K, f=f)
    sol = rl.solve(system, rl.HarmonicSet.full(6), rtol=1e-12)
    assert sol.success
    A = np.array([[kx - m * W**2, -c * W], [c * W, ky - m * W**2]])
    p = np.linalg.solve(A, m * ecc * W**2 * np.array([np.cos(beta), np.sin(beta)]))
    t = np.linspace(0, 2 * np.pi / W, 9)
    q = sol.evaluate(t)
    z = (p[0] + 1j * p[1]) * np.exp(1j * W * t)
    np.testing.assert_allclose(q[:, 0] + 1j * q[:, 1], z, atol=1e-10 * abs(z[0]))


def test_bad_input():
    with pytest.raises(ModelError, match="axis"):
        rotation_series([0, 0, 0], 1)
    with pytest.raises(ModelError, match="integer"):
        rotation_series([0, 0, 1], 1.5)
    with pytest.raises(ModelError, match="multiple of 3"):
        rotate_body_matrix(np.eye(4), [0, 0, 1], 1)
    with pytest.raises(ModelError, match="integer"):
        rotation_series([0, 0, 1], Fraction(1, 2))
    assert sorted(rotation_series([0, 0, 1], Fraction(4, 2))) == [-2, 0, 2]
    R0 = rotation_series([0, 0, 1], 0)
    assert sorted(R0) == [0] and np.array_equal(R0[0], np.eye(3))
