"""Outputs a user reads (bearing forces, dynamic transmission error, node harmonics with their
frequency in Hz and orders per shaft) against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

import rheolin as rl
from rheolin.mechanics import Model
from rheolin.results.outputs import bearing_forces, node_displacements, transmission_errors


@pytest.fixture(autouse=True)
def _allow_underflow():
    with np.errstate(under="ignore"):
        yield


def _unbalanced_rotor(m: float, k: float, c: float, U: float) -> Model:
    model = Model()
    model.add_rigid_body("rotor", (0, 0, 0), m, (0.01, 0.01, 0.02))
    model.add_disk("rotor", 0, unbalance=U, unbalance_angle=0.4)
    model.add_bearing("radial", "rotor", 0, k, c, components=("ux", "uy"))
    model.add_bearing(
        "rest", "rotor", 0, [1e7, 1e5, 1e5, 1e3], 10.0, components=("uz", "phix", "phiy", "phiz")
    )
    return model


@pytest.mark.parametrize("speed", [200.0, 316.0, 600.0])  # below, at, above sqrt(k/m)
def test_bearing_force_of_unbalanced_rigid_rotor_is_the_transmitted_force(speed):
    """Mass ``m`` on an isotropic spring-damper (k, c) with static unbalance ``U`` at speed W:
    orbit radius ``X = U W^2 / |k - m W^2 + i c W|``, transmitted force
    ``|F| = |k + i c W| X``, both at the 1x frequency ``W / 2 pi``."""
    m, k, c, U = 10.0, 1e6, 300.0, 2e-4
    a = _unbalanced_rotor(m, k, c, U).assemble(speed)
    sol = rl.solve(a.system, rl.HarmonicSet.closure(a.system, order=2))
    assert sol.success
    X = U * speed**2 / abs(k - m * speed**2 + 1j * c * speed)
    F = abs(k + 1j * c * speed) * X
    (row,) = [r for r in bearing_forces(sol, a, "radial") if r.harmonic == 1]
    assert row.frequency_hz == pytest.approx(speed / (2 * np.pi), rel=1e-14)
    assert row.orders == {"rotor": pytest.approx(1.0, rel=1e-14)}
    # circular whirl: each of Fx, Fy has single-sided amplitude |F|, 90 degrees apart
    Fx, Fy = row.value[0], row.value[1]
    assert 2 * abs(Fx) == pytest.approx(F, rel=1e-9)
    assert 2 * abs(Fy) == pytest.approx(F, rel=1e-9)
    assert abs(abs(np.angle(Fy / Fx)) - np.pi / 2) < 1e-9
    (disp,) = [r for r in node_displacements(sol, a, "rotor", 0) if r.harmonic == 1]
    assert 2 * abs(disp.value[0]) == pytest.approx(X, rel=1e-9)
    # the support carries F = (k + i c W) x: the force on the support follows the rotor
    assert Fx == pytest.approx((k + 1j * c * speed) * disp.value[0], rel=1e-12)


def test_static_bearing_forces_carry_the_weight():
    """A rigid rotor under gravity on two bearings at distances a and b from its centre of
    mass: the supports carry ``m g b / (a + b)`` and ``m g a / (a + b)`` downwards."""
    m, g, a_len, b_len = 12.0, 9.81, 0.1, 0.3
    model = Model()
    model.add_shaft(
        "rotor", [0.0, a_len, a_len + b_len], outer_diameter=0.05, elastic_modulus=2.1e11,
        density=0.0, material="steel"
    )  # fmt: skip
    model.add_disk("rotor", 1, mass=m, inertia=(0.05, 0.05, 0.08))
    model.add_bearing("left", "rotor", 0, 1e8, components=("ux", "uy", "uz", "phiz"))
    model.add_bearing("right", "rotor", 2, 1e8, components=("ux", "uy"))
    model.set_gravity((0.0, -g, 0.0))
    a = model.assemble(100.0)
    sol = rl.solve(a.system, [0], method="lti")
    left = bearing_forces(sol, a, "left")[0].value
    right = bearing_forces(sol, a, "right")[0].value
    assert left[1].real == pytest.approx(-m * g * b_len / (a_len + b_len), rel=1e-9)
    assert right[1].real == pytest.approx(-m * g * a_len / (a_len + b_len), rel=1e-9)
    assert abs(left[0]) < 1e-9 * m * g and abs(right[0]) < 1e-9 * m * g


def test_dynamic_transmission_error_of_a_torsional_gear_pair():
    """Two gears whose centres are held rigidly, free to rotate: the relative coordinate on
    the line of action ``delta = r_b1 theta_1 +- r_b2 theta_2`` obeys
    ``m_e delta'' + c delta' + k delta = k e`` (the static transmission error loads the mesh
    through its stiffness, Ozguven & Houser 1988) with ``1 / m_e = r_b1^2 / J_1 +
    r_b2^2 / J_2``, so at the mesh frequency ``w_m``
    ``delta / e = k / (k - m_e w_m^2 + i c w_m)``."""
    z1, z2, module, alpha = 20, 37, 3e-3, np.radians(20.0)
    J1, J2, k, c, e = 2e-3, 3e-2, 3e8, 900.0, 4e-6
    model = Model()
    model.add_rigid_body("pinion", (0, 0, 0), 1.5, (1e-3, 1e-3, J1))
    centre = module * (z1 + z2) / 2
    model.add_rigid_body("gear", (centre, 0, 0), 6.0, (2e-2, 2e-2, J2))
    stiff = [1e16, 1e16, 1e16, 1e13, 1e13]  # centres held: compliance 3e-8 of the mesh
    for body in ("pinion", "gear"):
        model.add_bearing(body, body, 0, stiff, components=("ux", "uy", "uz", "phix", "phiy"))
    model.add_gear_mesh(
        "mesh", "pinion", 0, "gear", 0, z1, z2, module, pressure_angle=alpha, stiffness=k,
        damping=c, transmission_error={1: e / 2},
    )  # fmt: skip
    rb1 = module * z1 * np.cos(alpha) / 2
    rb2 = module * z2 * np.cos(alpha) / 2
    me = 1.0 / (rb1**2 / J1 + rb2**2 / J2)
    for W in (300.0, np.sqrt(k / me) / z1, 1500.0):  # below, at and above mesh resonance
        a = model.assemble(W)
        (mesh_h,) = a.plan.mesh
        sol = rl.solve(a.system, [mesh_h])  # n = 0 left out: the free rotation is singular
        assert sol.success
        wm = z1 * W
        ratio = k / (k - me * wm**2 + 1j * c * wm)
        (row,) = [r for r in transmission_errors(sol, a, "mesh") if r.harmonic == mesh_h]
        assert 2 * abs(row.value[0]) == pytest.approx(e * abs(ratio), rel=1e-6)
        assert row.frequency_hz == pytest.approx(wm / (2 * np.pi), rel=1e-14)
        assert row.orders["pinion"] == pytest.approx(z1, rel=1e-14)
        assert row.orders["gear"] == pytest.approx(z2, rel=1e-14)
