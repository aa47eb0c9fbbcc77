"""Model-level checks against independent references: beam formula, asymmetric-rotor closed
form, and a BDF time integration of the same assembled geared system."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import rheolin as rl
from rheolin.errors import ModelError
from rheolin.mechanics.model import Model
from rheolin.mechanics.sections import general_section, solid_circular


@pytest.fixture(autouse=True)
def _allow_underflow():
    """Hill eigenvectors have negligibly small far harmonics; underflow there is harmless."""
    with np.errstate(under="ignore"):
        yield


def test_gravity_sag_of_simply_supported_timoshenko_shaft():
    """Midspan sag = 5 w L^4 / (384 E I) + w L^2 / (8 kappa G A), w = rho A g."""
    E, nu, rho, d, L, g = 2.1e11, 0.3, 7850.0, 0.1, 0.5, 9.81
    model = Model()
    model.add_shaft(
        "shaft",
        np.linspace(0, L, 9),
        outer_diameter=d,
        elastic_modulus=E,
        poisson_ratio=nu,
        density=rho,
    )
    model.add_bearing("left", "shaft", 0, 1e14, components=("ux", "uy", "uz", "phiz"))
    model.add_bearing("right", "shaft", 8, 1e14, components=("ux", "uy"))
    model.set_gravity((0.0, -g, 0.0))
    a = model.assemble(speed=50.0)
    assert a.system.time_invariant and a.system.load_harmonics == [0]
    q = rl.solve(a.system, [0], method="lti").harmonic(0).real
    uy = q[a.dofs("shaft", 4)[1]] - 0.5 * (q[a.dofs("shaft", 0)[1]] + q[a.dofs("shaft", 8)[1]])
    sec = solid_circular(d, nu)
    w = rho * sec.area * g
    bending = 5 * w * L**4 / (384 * E * sec.Iy)
    shear = w * L**2 / (8 * sec.kappa_y * E / (2 * (1 + nu)) * sec.area)
    assert shear > 0.05 * bending  # a stubby shaft: shear matters
    assert abs(-uy - (bending + shear)) < 1e-9 * (bending + shear)
    assert np.allclose(q[a.dofs("shaft", 4)[[0, 2]]], 0.0, atol=1e-12 * bending)


def _asymmetric_rotor(I1, I2, E, L, m, c):
    model = Model()
    model.add_shaft(
        "rotor",
        [0, L / 2, L],
        section=general_section(1e-3, I1, I2, I1 + I2),
        elastic_modulus=E,
        density=0.0,
        material="steel",
    )
    model.add_disk("rotor", 1, mass=m, inertia=(0.02, 0.02, 0.04))
    model.add_bearing("left", "rotor", 0, 1e11, components=("ux", "uy", "uz", "phiz"))
    model.add_bearing("right", "rotor", 2, 1e11, components=("ux", "uy"))
    model.add_bearing("damper", "rotor", 1, 0.0, [c, c, c, 1.0, 1.0, 1.0], components=None)
    return model


def test_asymmetric_shaft_instability_band_between_critical_speeds():
    """Massless shaft (I1 != I2), disk at midspan, rigid supports, stationary damping c:
    k_i = 48 E I_i / L^3, unstable iff (k1 - m W^2)(k2 - m W^2) + c^2 W^2 < 0."""
    E, L, I1, I2, m, c = 2.1e11, 0.6, 2.0e-8, 2.6e-8, 5.0, 20.0
    k1, k2 = 48 * E * I1 / L**3, 48 * E * I2 / L**3
    x = np.roots([m * m, c * c - m * (k1 + k2), k1 * k2])
    lo, hi = np.sqrt(np.sort(x.real))
    assert np.sqrt(k1 / m) < lo < hi < np.sqrt(k2 / m)
    model = _asymmetric_rotor(I1, I2, E, L, m, c)
    for frac in (-0.1, 0.1, 0.5, 0.9, 1.1):
        W = lo + frac * (hi - lo)
        res = rl.floquet(model.assemble(W).system, 4)
        expected_unstable = (k1 - m * W**2) * (k2 - m * W**2) + c**2 * W**2 < 0
        assert expected_unstable == (0 < frac < 1)
        assert res.stable == (not expected_unstable), (frac, res.max_real)


def _geared_model():
    model = Model()
    model.add_rigid_body("pinion", (0, 0, 0), 1.0, (5e-4, 5e-4, 4e-4))
    model.add_rigid_body("gear", (0.05, 0, 0), 2.0, (1.5e-3, 1.5e-3, 1.2e-3))
    model.add_disk("pinion", 0, unbalance=2e-5, unbalance_angle=0.3)
    model.add_disk("gear", 0, unbalance=4e-5, unbalance_angle=-1.0, couple_unbalance=2e-6)
    for body in ("pinion", "gear"):
        model.add_bearing(
            body + "_bearing",
            body,
            0,
            [1e6, 1e6, 1e6, 2e3, 2e3, 50.0],
            [400.0, 400.0, 400.0, 0.4, 0.4, 0.1],
            components=None,
        )
    model.add_gear_mesh(
        "mesh",
        "pinion",
        0,
        "gear",
        0,
        10,
        15,
        module=4e-3,
        helix_angle=np.radians(12),
        contact_ratio=1.6,
        single_stiffness=1.6e6,
        double_stiffness=2.4e6,
        stiffness_harmonics=2,
        damping=450.0,
        transmission_error={1: 2e-6, 2: 0.5e-6j},
    )
    return model


def _time_domain(system, t_end):
    """BDF on y = (q, v) with M(t), D(t), K(t), f(t) summed from the same coefficients."""
    n, w1 = system.n, system.omega
    ks = sorted(set(system.M) | set(system.D) | set(system.K) | set(system.f))
    rows = []
    for k in ks:
        parts = [system.coefficient(name, k) for name in "MDK"]
        dense = [np.zeros(n * n) if p is None else p.toarray().ravel() for p in parts]
        rows.append(np.concatenate([*dense, system.load(k)]))
    table, ks = np.array(rows, dtype=complex), np.array(ks)

    def rhs(t, y):
        x = (np.exp(1j * ks * w1 * t) @ table).real
        M, D, K = (x[i * n * n : (i + 1) * n * n].reshape(n, n) for i in range(3))
        q, v = y[:n], y[n:]
        return np.concatenate([v, np.linalg.solve(M, x[3 * n * n :] - K @ q - D @ v)])

    def jac(t, y):
        x = (np.exp(1j * ks * w1 * t) @ table).real
        M, D, K = (x[i * n * n : (i + 1) * n * n].reshape(n, n) for i in range(3))
        Mi = np.linalg.inv(M)
        return np.block([[np.zeros((n, n)), np.eye(n)], [-Mi @ K, -Mi @ D]])

    return solve_ivp(
        rhs,
        (0.0, t_end),
        np.zeros(2 * n),
        method="BDF",
        rtol=1e-7,
        atol=1e-18,
        jac=jac,
        dense_output=True,
    )


def test_geared_pair_with_unbalance_matches_time_integration():
    a = _geared_model().assemble(speed=100.0)
    assert a.plan.spin == {"pinion": 3, "gear": -2} and a.plan.mesh == (30,)
    assert a.generators == [2, 3, 30]
    H = rl.HarmonicSet.closure(a.system, order=40, max_harmonic=300)
    sol = rl.solve(a.system, H)
    assert sol.success and sol.residual < 1e-9
    T = 2 * np.pi / a.omega
    ivp = _time_domain(a.system, 2.5 * T)
    assert ivp.success
    t = np.linspace(1.5 * T, 2.5 * T, 60)  # transients have decayed (slowest ~ 0.1 s)
    ref = ivp.sol(t)[: a.system.n].T
    err = np.abs(sol.evaluate(t) - ref).max() / np.abs(ref).max()
    assert err < 1e-6, err


def test_model_errors_name_the_field():
    model = Model()
    with pytest.raises(ModelError, match="positions"):
        model.add_shaft("s", [0.0, 0.0], outer_diameter=0.02, material="steel")
    model.add_shaft("s", [0.0, 0.5], outer_diameter=0.02, material="steel")
    with pytest.raises(ModelError, match="name"):
        model.add_shaft("s", [0.0, 0.5], outer_diameter=0.02, material="steel")
    with pytest.raises(ModelError, match="body"):
        model.add_disk("nope", 0, mass=1.0, inertia=(1, 1, 1))
    model.add_rigid_body("g", (0.01, 0, 0), 1.0, (1, 1, 1))
    with pytest.raises(ModelError, match="gear_body"):
        model.add_gear_mesh("m", "s", 0, "s", 1, 10, 20, module=2e-3, stiffness=1e8)
    with pytest.raises(ModelError, match="stiffness"):
        model.add_gear_mesh("m", "s", 0, "g", 0, 10, 20, module=2e-3)
    model.add_gear_mesh("m", "s", 0, "g", 0, 10, 20, module=2e-3, stiffness=1e8)
    with pytest.raises(ModelError, match="centre distance"):
        model.assemble(10.0)
    with pytest.raises(ModelError, match="speed"):
        model.assemble(-1.0)
