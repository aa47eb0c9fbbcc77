"""Batched speed sweep of a time-invariant model against closed forms and per-speed solves."""

from __future__ import annotations

import numpy as np
import pytest

import rheolin as rl
from rheolin.mechanics import Model
from rheolin.results.speeds import lti_speeds


@pytest.fixture(autouse=True)
def _allow_underflow():
    with np.errstate(under="ignore"):
        yield


def test_rigid_rotor_on_anisotropic_bearing_matches_the_closed_form():
    """A rotating force F cos(Wt) along x on mass m with (kx, cx): x = F / (kx - m W^2 + i cx W)
    at every speed, below, near and above sqrt(kx/m); y and the rotations stay at rest."""
    m, kx, ky, cx, F = 3.0, 3e4, 5e4, 12.0, 2.0
    model = Model()
    model.add_rigid_body("r", (0, 0, 0), m, (0.1, 0.1, 0.2))
    model.add_bearing("b", "r", 0, [kx, ky], [cx, cx])
    model.add_bearing("rest", "r", 0, 1e5, 1.0, components=("uz", "phix", "phiy", "phiz"))
    model.add_force("f", "r", 0, force=(F, 0, 0), order=1)
    W = np.linspace(5.0, 300.0, 240)
    out = lti_speeds(model.speed_template(), W)
    assert out.harmonics.tolist() == [1] and out.success.all()
    x = 2 * out.q[:, 0, 0]
    np.testing.assert_allclose(x, F / (kx - m * W**2 + 1j * cx * W), rtol=1e-12)
    assert np.abs(out.q[:, 0, 1:]).max() <= 1e-14 * np.abs(x).max()


def test_gyroscopic_shaft_matches_per_speed_solves_and_custom_loads():
    """A spinning Timoshenko shaft with a disk (gyroscopic, speed dependent): the batch equals
    ``rl.solve`` of each assembled speed; a load callable replaces the model's loads."""
    model = Model()
    model.add_shaft("s", np.linspace(0, 0.9, 7), outer_diameter=0.04, material="steel")
    model.add_disk("s", 3, outer_diameter=0.25, width=0.04, material="steel")
    model.add_bearing("a", "s", 0, 2e7, 300.0, components=("ux", "uy", "uz", "phiz"))
    model.add_bearing("b", "s", 6, 2e7, 300.0)
    model.add_force("f", "s", 3, force=(10.0, 0, 0), order=1)
    template = model.speed_template()
    speeds = np.array([50.0, 400.0, 1200.0])
    out = lti_speeds(template, speeds)
    for i, W in enumerate(speeds):
        a = model.assemble(W)
        ref = rl.solve(a.system, [1], method="lti", stability=False).harmonic(1)
        np.testing.assert_allclose(out.q[i, 0], ref, rtol=0, atol=1e-10 * np.abs(ref).max())
    ux = 6 * 3

    def unbalance(w1: np.ndarray, n: int) -> np.ndarray:
        f = np.zeros((w1.size, template.n_dof), dtype=complex)
        f[:, ux], f[:, ux + 1] = 1e-4 * w1**2 / 2, -1j * 1e-4 * w1**2 / 2
        return f

    forced = lti_speeds(template, speeds, [1], loads=unbalance)
    for i, W in enumerate(speeds):
        a = model.assemble(W)
        s = rl.PeriodicSystem(a.omega, M=a.system.M, D=a.system.D, K=a.system.K,
                              f={1: unbalance(np.array([a.omega]), 1)[0]})  # fmt: skip
        ref = rl.solve(s, [1], method="lti", stability=False).harmonic(1)
        np.testing.assert_allclose(forced.q[i, 0], ref, rtol=0, atol=1e-10 * np.abs(ref).max())


def test_time_varying_model_is_refused():
    model = Model()
    model.add_rigid_body("r", (0, 0, 0), 1.0, (0.1, 0.1, 0.2))
    model.add_disk("r", 0, unbalance=1e-4)
    model.add_bearing("b", "r", 0, 1e5, 1.0, components=None)
    with pytest.raises(ValueError, match="time-invariant"):
        lti_speeds(model.speed_template(), [10.0])
