"""Harmonic balance against time integration (``scipy.integrate.solve_ivp``, BDF).

The time functions are written here as cosine/sine series (``X(t) = C_0 + sum_k C_k cos k w t
+ S_k sin k w t``); the Fourier coefficients handed to rheolin are ``X_k = (C_k - i S_k) / 2``,
so the convention of docs/conventions.md is under test too. The ODE ``M(t) q'' + D(t) q' + K(t) q =
f(t)`` is integrated from rest until the transient has decayed, then the last period is
compared with ``Solution.evaluate``.

Tolerance: BDF runs at ``rtol = 1e-10``; its global error is checked in the test against
DOP853 at ``rtol = 1e-12`` (agreement < 1e-8 relative). The transient left after > 20 decay
times is ``< e^{-20} = 2e-9`` of the response, and the harmonic truncation (coefficients
decaying geometrically, |H| chosen so the last ones are < 1e-12) adds nothing visible. A
relative error below 1e-6 leaves two orders of margin for the reference and still catches any
convention error (a wrong sign or factor 2 in one coefficient gives errors ~1e-2..1).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest
import scipy.sparse as sp
from cases import gravity_rotor, integrate

import rheolin as rl


@dataclass
class Trig:
    """``X(t) = C[0] + sum_k C[k] cos(k w t) + S[k] sin(k w t)`` for each of M, D, K, f."""

    omega: float
    C: dict[str, dict[int, np.ndarray]]
    S: dict[str, dict[int, np.ndarray]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # one (kmax + 1, n^2) cosine and sine table per name for a fast evaluation
        kmax = max(max(d) for d in (*self.C.values(), *self.S.values()) if d)
        self._k = np.arange(kmax + 1)
        self._tables = {}
        for name in ("M", "D", "K", "f"):
            shape = np.shape(self.C[name][0])
            cos_t = np.zeros((kmax + 1, int(np.prod(shape))))
            sin_t = np.zeros_like(cos_t)
            for k, c in self.C[name].items():
                cos_t[k] = np.ravel(c)
            for k, v in self.S.get(name, {}).items():
                sin_t[k] = np.ravel(v)
            self._tables[name] = (cos_t, sin_t, shape)

    def at(self, name: str, t: float) -> np.ndarray:
        cos_t, sin_t, shape = self._tables[name]
        phase = self._k * (self.omega * t)
        return (np.cos(phase) @ cos_t + np.sin(phase) @ sin_t).reshape(shape)

    def coefficients(self, name: str) -> dict[int, np.ndarray]:
        ks = set(self.C[name]) | set(self.S.get(name, {}))
        out = {}
        for k in sorted(ks):
            c = self.C[name].get(k, 0.0)
            s = self.S.get(name, {}).get(k, 0.0)
            out[k] = np.asarray(c, dtype=float) if k == 0 else (c - 1j * np.asarray(s)) / 2
        return out

    def system(self, sparse: bool = False) -> rl.PeriodicSystem:
        conv = sp.csr_array if sparse else (lambda x: x)
        mats = {
            name: {k: conv(v) for k, v in self.coefficients(name).items()}
            for name in ("M", "D", "K")
        }
        return rl.PeriodicSystem(self.omega, **mats, f=self.coefficients("f"))


def _sym(rng: np.random.Generator, n: int, scale: float) -> np.ndarray:
    a = rng.standard_normal((n, n))
    return scale * (a + a.T) / 2


def varying_2dof() -> Trig:
    """M, D and K all vary at w; K also at 2w; loads at w and 3w."""
    rng = np.random.default_rng(1)
    n = 2
    M0 = np.array([[2.0, 0.3], [0.3, 1.0]])
    K0 = np.array([[30.0, -10.0], [-10.0, 20.0]])
    D0 = 0.1 * K0 + 4.0 * M0
    return Trig(
        omega=1.7,
        C={
            "M": {0: M0, 1: _sym(rng, n, 0.15)},
            "D": {0: D0, 1: _sym(rng, n, 0.1)},
            "K": {0: K0, 1: _sym(rng, n, 3.0), 2: _sym(rng, n, 2.0)},
            "f": {0: np.zeros(n), 1: np.array([1.0, 0.0]), 3: np.array([0.0, 0.5])},
        },
        S={
            "M": {1: _sym(rng, n, 0.1)},
            "D": {2: _sym(rng, n, 0.1)},
            "K": {2: _sym(rng, n, 1.5)},
            "f": {1: np.array([0.0, 0.7])},
        },
    )


def varying_3dof() -> Trig:
    """A 3-DOF chain: mass modulated at 2w, damping at w, stiffness at w and 3w (a mesh-like
    rank-1 term), a static load and a load at 2w; non-symmetric D_1 (a circulatory part)."""
    rng = np.random.default_rng(7)
    n = 3
    k = np.array([40.0, 25.0, 30.0, 15.0])
    K0 = np.array(
        [[k[0] + k[1], -k[1], 0.0], [-k[1], k[1] + k[2], -k[2]], [0.0, -k[2], k[2] + k[3]]]
    )
    M0 = np.diag([1.0, 1.5, 0.8])
    D0 = 0.08 * K0 + 5.0 * M0
    w = np.array([0.0, 1.0, -1.0])
    return Trig(
        omega=2.3,
        C={
            "M": {0: M0, 2: np.diag([0.1, -0.2, 0.05])},
            "D": {0: D0, 1: 0.1 * rng.standard_normal((n, n))},
            "K": {0: K0, 1: 4.0 * np.outer(w, w), 3: 1.5 * np.outer(w, w)},
            "f": {0: np.array([0.0, 0.0, -1.0]), 2: np.array([1.0, 0.0, 0.0])},
        },
        S={"K": {3: -1.0 * np.outer(w, w)}, "f": {2: np.array([0.0, 0.5, 0.0])}},
    )


def lti_3dof() -> Trig:
    """Time-invariant coefficients, loads at w and 2w (for ``lti``)."""
    t = varying_3dof()
    C = {name: {0: t.C[name][0]} for name in ("M", "D", "K")}
    C["f"] = {0: np.zeros(3), 1: np.array([1.0, -0.5, 0.0]), 2: np.array([0.0, 0.0, 2.0])}
    return Trig(omega=t.omega, C=C, S={"f": {1: np.array([0.3, 0.0, 0.0])}})


def steady_state_by_integration(trig: Trig, periods: int) -> tuple[np.ndarray, np.ndarray]:
    """Integrate from rest for ``periods`` periods; return (t, q) over the last period, after
    checking that the last two periods agree (the transient has decayed)."""
    n = trig.C["M"][0].shape[0]
    T = 2 * np.pi / trig.omega

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        q, v = x[:n], x[n:]
        acc = np.linalg.solve(
            trig.at("M", t), trig.at("f", t) - trig.at("D", t) @ v - trig.at("K", t) @ q
        )
        return np.concatenate([v, acc])

    def jac(t: float, x: np.ndarray) -> np.ndarray:
        Minv = np.linalg.inv(trig.at("M", t))
        return np.block(
            [[np.zeros((n, n)), np.eye(n)], [-Minv @ trig.at("K", t), -Minv @ trig.at("D", t)]]
        )

    t_end = periods * T
    t_eval = np.linspace(t_end - 2 * T, t_end, 121)
    sol = integrate(
        rhs,
        (0.0, t_end),
        np.zeros(2 * n),
        method="BDF",
        jac=jac,
        t_eval=t_eval,
        rtol=1e-10,
        atol=1e-14,
    )
    assert sol.success, sol.message
    q = sol.y[:n].T
    prev, last = q[:61], q[60:]
    scale = np.abs(q).max()
    assert np.abs(last - prev).max() < 1e-7 * scale, "transient has not decayed"
    # the reference's own error: an independent high-order explicit integrator must agree
    check = integrate(
        rhs,
        (0.0, t_end),
        np.zeros(2 * n),
        method="DOP853",
        t_eval=t_eval[60:],
        rtol=1e-12,
        atol=1e-16,
    )
    assert np.abs(check.y[:n].T - last).max() < 1e-8 * scale
    return t_eval[60:], last


def _decay_periods(system: rl.PeriodicSystem, decays: float = 22.0) -> int:
    """Periods needed for ``decays`` e-foldings of the slowest mode, plus one (the
    periodicity check compares the last two periods). The decay rate only sizes the run; the
    periodicity check verifies it independently."""
    rate = -rl.floquet(system, 12).max_real
    assert rate > 0, "the test system must be stable"
    return int(np.ceil(decays / rate / (2 * np.pi / system.omega))) + 1


@pytest.fixture(
    scope="module",
    params=[varying_2dof, varying_3dof, lti_3dof],
    ids=["2dof_MDK", "3dof_mesh", "3dof_lti"],
)
def integrated(request: pytest.FixtureRequest):
    trig = request.param()
    periods = _decay_periods(trig.system())
    t, q = steady_state_by_integration(trig, periods)
    return trig, t, q


@pytest.mark.parametrize("sparse", [False, True], ids=["dense", "sparse"])
@pytest.mark.parametrize("method", ["lti", "perturbation", "gmres", "direct"])
def test_against_time_integration(integrated, method: str, sparse: bool) -> None:
    trig, t, q_ref = integrated
    system = trig.system(sparse=sparse)
    if method == "lti" and not system.time_invariant:
        pytest.skip(
            "lti applies to time-invariant systems only (refusal tested in test_solvers.py)"
        )
    sol = rl.solve(system, 25, method=method, rtol=1e-12)
    assert sol.success, sol.message
    err = np.abs(sol.evaluate(t) - q_ref).max() / np.abs(q_ref).max()
    assert err < 1e-6, err


def test_time_variation_matters(integrated) -> None:
    """The comparison is sensitive: dropping dA (solving the time-averaged system) misses the
    integrated response by far more than the tolerance."""
    trig, t, q_ref = integrated
    system = trig.system()
    if system.time_invariant:
        pytest.skip("nothing varies")
    averaged = rl.PeriodicSystem(
        system.omega, M={0: system.M[0]}, D={0: system.D[0]}, K={0: system.K[0]}, f=system.f
    )
    sol = rl.solve(averaged, 25, method="lti")
    err = np.abs(sol.evaluate(t) - q_ref).max() / np.abs(q_ref).max()
    assert err > 1e-2, err


def test_positive_definite_mass() -> None:
    """The test systems' M(t) stays positive definite over a period."""
    for trig in (varying_2dof(), varying_3dof()):
        for t in np.linspace(0, 2 * np.pi / trig.omega, 50):
            assert np.linalg.eigvalsh(trig.at("M", t)).min() > 0.1


def test_gravity_rotor_against_shooting() -> None:
    """The docs/solvers.md case (perturbation diverges, rotor stable): the periodic solution by
    shooting (state transition over one period of ``K(t)``, ``T = pi / W``) against gmres."""
    rotor = gravity_rotor()
    f = rotor.coefficients()[3]
    W, T = rotor.W, np.pi / rotor.W

    def Kt(t: float) -> np.ndarray:
        c, s = np.cos(2 * W * t), np.sin(2 * W * t)
        return rotor.km * np.eye(2) + rotor.kd * np.array([[c, s], [s, -c]])

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        # 5 trajectories at once: column 0 forced from rest, columns 1..4 homogeneous
        X = x.reshape(4, 5)
        q, v = X[:2], X[2:]
        force = np.zeros((2, 5))
        force[:, 0] = f[0]
        acc = (force - rotor.c * v - Kt(t) @ q) / rotor.m
        return np.vstack([v, acc]).ravel()

    x0 = np.hstack([np.zeros((4, 1)), np.eye(4)]).ravel()
    out = integrate(rhs, (0.0, T), x0, method="DOP853", rtol=1e-12, atol=1e-16)
    X = out.y[:, -1].reshape(4, 5)
    phi, particular = X[:, 1:], X[:, 0]
    start = np.linalg.solve(np.eye(4) - phi, particular)  # x(T) = phi x(0) + p = x(0)
    t = np.linspace(0, T, 41)

    def rhs1(t: float, x: np.ndarray) -> np.ndarray:
        return np.concatenate([x[2:], (f[0] - rotor.c * x[2:] - Kt(t) @ x[:2]) / rotor.m])

    ref = (
        integrate(rhs1, (0.0, T), start, method="DOP853", t_eval=t, rtol=1e-12, atol=1e-16).y[:2].T
    )
    sol = rl.solve(rotor.system(), 16, method="gmres")
    assert sol.success and sol.iterations < 10
    err = np.abs(sol.evaluate(t) - ref).max() / np.abs(ref).max()
    assert err < 1e-7, err
    # the dynamic part is large: q_{±2} is a resonant response to the static sag
    assert np.abs(sol.harmonic(2)).max() > 0.5 * np.abs(sol.harmonic(0)).max()
