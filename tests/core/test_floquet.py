"""Floquet stability by Hill's method against independent references.

* Mathieu ``y'' + (a - 2 q cos 2t) y = 0``: transition curves from ``scipy.special`` and
  growth rates from the monodromy matrix (``solve_ivp`` over one period).
* Damped Mathieu: ``y = e^{-ct/2} u`` maps it onto Mathieu with ``a - c^2/4``.
* Isotropic shaft with rotating internal damping: threshold ``W_th = w_n (1 + c_n/c_r)``,
  circulatory stiffness built by sampling ``R D_B R'^T`` in time.
* Asymmetric Jeffcott rotor: closed-form unstable band (docs/solvers.md, reference cases).
"""

from __future__ import annotations

import numpy as np
import pytest
from cases import Jeffcott, integrate
from scipy.special import mathieu_a, mathieu_b

import rheolin as rl

HILL_N = 12


def mathieu_system(a: float, q: float, c: float = 0.0) -> rl.PeriodicSystem:
    """``y'' + c y' + (a - 2 q cos 2t) y = 0``: omega = 2, K_{±1} = -q."""
    return rl.PeriodicSystem(
        2.0, M={0: np.eye(1)}, D={0: c * np.eye(1)}, K={0: a * np.eye(1), 1: -q * np.eye(1)}
    )


def monodromy(a: float, q: float, c: float = 0.0) -> np.ndarray:
    """Monodromy matrix over the period ``pi`` by DOP853 (independent of Hill's method)."""

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        y, v = x[:2], x[2:]
        return np.concatenate([v, -c * v - (a - 2 * q * np.cos(2 * t)) * y])

    sol = integrate(
        rhs, (0.0, np.pi), [1.0, 0.0, 0.0, 1.0], method="DOP853", rtol=1e-13, atol=1e-15
    )
    return sol.y[:, -1].reshape(2, 2).T


def mathieu_growth(a: float, q: float) -> float:
    """Largest Floquet real part of undamped Mathieu from the trace of the monodromy
    (``det = 1``: multipliers ``r, 1/r`` with ``r + 1/r = tr``)."""
    tr = abs(np.trace(monodromy(a, q)))
    return float(np.arccosh(tr / 2) / np.pi) if tr > 2 else 0.0


def _curves(q: float) -> list[tuple[str, float, float]]:
    """(name, value, distance to the nearest other curve) in increasing order of value."""
    vals = [("a0", mathieu_a(0, q))]
    for m in range(1, 6):
        vals += [(f"b{m}", mathieu_b(m, q)), (f"a{m}", mathieu_a(m, q))]
    out = []
    for i, (name, v) in enumerate(vals):
        gaps = [abs(vals[j][1] - v) for j in (i - 1, i + 1) if 0 <= j < len(vals)]
        out.append((name, float(v), float(min(gaps))))
    return out


MATHIEU_POINTS = [
    pytest.param(q, name, value, width, id=f"q{q}-{name}")
    for q in (0.3, 1.0, 3.0)
    for name, value, width in _curves(q)
    if width > 1e-6  # b5, a5 at q = 0.3 are 3e-8 apart: below what a test can resolve
]


@pytest.mark.parametrize(("q", "name", "value", "width"), MATHIEU_POINTS)
def test_mathieu_transition_curves(q: float, name: str, value: float, width: float) -> None:
    """Unstable below a0 and inside (b_m, a_m); stable (and marginal: undamped) outside.

    Probe at 1 % of the distance to the nearest other curve on either side."""
    delta = 0.01 * width
    # which side is unstable: below a0, above b_m, below a_m
    unstable_side = -1 if name.startswith("a") else +1
    for side in (-1, +1):
        a = value + side * delta
        res = rl.floquet(mathieu_system(a, q), HILL_N)
        growth = mathieu_growth(a, q)
        assert len(res.exponents) == 2
        if side == unstable_side:
            assert not res.stable, f"a={a}: Hill says stable, max_real={res.max_real}"
            assert res.max_real > 0
            if growth > 1e-4:  # the trace resolves growth rates above ~1e-6 only
                assert res.max_real == pytest.approx(growth, rel=1e-5)
        else:
            assert res.stable and res.marginal, f"a={a}: max_real={res.max_real}"
            assert growth == 0.0  # the independent reference agrees on the side
            np.testing.assert_allclose(res.exponents.real, 0.0, atol=res.tol)


def test_mathieu_exponents_sum_to_zero() -> None:
    """Liouville: with no damping the exponents sum to 0 (mod i w); in a band they are ±mu."""
    a = 0.5 * (mathieu_b(1, 1.0) + mathieu_a(1, 1.0))
    res = rl.floquet(mathieu_system(a, 1.0), HILL_N)
    mu = mathieu_growth(a, 1.0)
    assert np.sort(res.exponents.real) == pytest.approx([-mu, mu], rel=1e-8)


@pytest.mark.parametrize("c", [0.05, 0.2])
@pytest.mark.parametrize(
    ("kind", "m", "q"), [("a", 0, 1.0), ("b", 1, 1.0), ("a", 1, 3.0), ("b", 2, 0.3), ("a", 2, 3.0)]
)
def test_damped_mathieu_on_shifted_curve(c: float, kind: str, m: int, q: float) -> None:
    """On ``a = a_m(q) + c^2/4`` the reduced equation sits on a transition curve (exponent
    real part 0), so the damped exponents all have real part exactly ``-c/2``."""
    curve = mathieu_a(m, q) if kind == "a" else mathieu_b(m, q)
    res = rl.floquet(mathieu_system(curve + c * c / 4, q, c), HILL_N)
    # a double multiplier on the curve: Hill's eigenvalues are accurate to ~sqrt(eps)
    np.testing.assert_allclose(res.exponents.real, -c / 2, atol=1e-6)


@pytest.mark.parametrize(("m", "q"), [(1, 1.0), (1, 3.0), (2, 3.0), (3, 3.0)])
def test_damped_mathieu_inside_band(m: int, q: float) -> None:
    """Mid-band: the damped exponents are ``mu - c/2`` with ``mu`` the undamped growth rate;
    damping above ``2 mu`` stabilizes.  Reference: monodromy of the damped equation."""
    mid = 0.5 * (mathieu_b(m, q) + mathieu_a(m, q))
    mu = mathieu_growth(mid, q)
    for c in (0.5 * mu, 4.0 * mu):
        a = mid + c * c / 4
        res = rl.floquet(mathieu_system(a, q, c), HILL_N)
        mult = np.linalg.eigvals(monodromy(a, q, c))
        ref = np.log(np.abs(mult)).max() / np.pi
        assert res.max_real == pytest.approx(ref, rel=1e-6, abs=1e-9)
        assert res.max_real == pytest.approx(mu - c / 2, rel=1e-6)
        assert res.stable == (c > 2 * mu)


# --------------------------------------------------------------------------- rotating damping
def rotating_damping_system(W: float, m: float, k: float, c_n: float, c_r: float):
    """Isotropic 2-DOF Jeffcott: stationary damping ``c_n``, rotating damping ``c_r``.

    docs/rotating-bodies.md: ``D += R D_B R^T`` and ``K += R D_B R'^T`` with ``D_B = c_r I`` in body
    axes. Both are sampled at 16 times over one revolution and Fourier transformed, so the
    coefficients do not rely on the closed form ``c_r W [[0, 1], [-1, 0]]``.
    """
    n_t = 16
    t = 2 * np.pi / W * np.arange(n_t) / n_t
    DB = c_r * np.eye(2)

    def R(th: float) -> np.ndarray:
        return np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])

    def dR(th: float) -> np.ndarray:
        return W * np.array([[-np.sin(th), -np.cos(th)], [np.cos(th), -np.sin(th)]])

    Dt = np.array([R(W * tt) @ DB @ R(W * tt).T for tt in t])
    Kt = np.array([R(W * tt) @ DB @ dR(W * tt).T for tt in t])
    # X_k = (1/n_t) sum_j X(t_j) e^{-i k W t_j}
    Dk, Kk = np.fft.fft(Dt, axis=0) / n_t, np.fft.fft(Kt, axis=0) / n_t
    D = {0: c_n * np.eye(2) + Dk[0].real}
    K = {0: k * np.eye(2) + Kk[0].real}
    for h in range(1, n_t // 2):
        if np.abs(Dk[h]).max() > 1e-12 * c_r:
            D[h] = Dk[h]
        if np.abs(Kk[h]).max() > 1e-12 * c_r * W:
            K[h] = Kk[h]
    return rl.PeriodicSystem(W, M={0: m * np.eye(2)}, D=D, K=K)


@pytest.mark.parametrize("ratio", [0.0, 0.5, 2.0])
def test_rotating_damping_threshold(ratio: float) -> None:
    m, k, c_r = 2.0, 800.0, 0.4
    c_n = ratio * c_r
    w_n = np.sqrt(k / m)
    W_th = w_n * (1 + c_n / c_r)
    for factor, stable in ((0.999, True), (1.001, False)):
        W = factor * W_th
        s = rotating_damping_system(W, m, k, c_n, c_r)
        assert s.time_invariant  # the circulatory term of an isotropic shaft is constant
        np.testing.assert_allclose(
            s.K[0], k * np.eye(2) + c_r * W * np.array([[0, 1], [-1, 0]]), atol=1e-12 * k
        )
        res = rl.floquet(s, 2)
        assert res.stable == stable, (factor, res.max_real)
        # z = x + i y: m z'' + (c_n + c_r) z' + (k - i c_r W) z = 0 and its conjugate
        roots = np.roots([m, c_n + c_r, k - 1j * c_r * W])
        assert res.max_real == pytest.approx(roots.real.max(), rel=1e-8)


@pytest.mark.parametrize("W", [0.3, 0.85, 0.95, 1.0, 1.05, 1.2, 2.0])
def test_asymmetric_rotor_band(W: float) -> None:
    """Unstable iff ``(k_x - m W^2)(k_y - m W^2) + c^2 W^2 < 0`` (docs/solvers.md, reference
    cases)."""
    rotor = Jeffcott(W=W, e=0.0)
    M, D, K, _ = rotor.coefficients()
    s = rl.PeriodicSystem(W, M={0: M[0]}, D={0: D[0]}, K={0: K[0], 2: K[2]})
    res = rl.floquet(s, 12)
    assert res.stable == (not rotor.unstable)
    assert len(res.exponents) == 4


def test_floquet_refuses_huge_dense_hill_matrix() -> None:
    s = rl.PeriodicSystem(1.0, M={0: np.eye(200)}, K={0: np.eye(200), 1: 0.1 * np.eye(200)})
    with pytest.raises(ValueError, match="`harmonics`"):
        rl.floquet(s, 20, method="dense")
