"""Speed-dependent bearings: interpolation, and use at the operating speed by every solver."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import PchipInterpolator, make_interp_spline

import rheolin as rl
from rheolin.errors import ModelError
from rheolin.mechanics.model import Model
from rheolin.results.speeds import lti_speeds
from rheolin.stability.campbell import campbell

SPEEDS = [50.0, 150.0, 300.0, 500.0]
KXX = [1e6, 2.5e6, 3e6, 3.2e6]
KXY = [2e5, 6e5, 1.1e6, 1.6e6]
CXX = [300.0, 250.0, 200.0, 180.0]


def _rotor(interp="cubic", speeds=SPEEDS):
    m = Model()
    m.add_shaft("s", [0.0, 0.3, 0.6], outer_diameter=0.04, material="steel")
    m.add_disk("s", 1, outer_diameter=0.25, width=0.04, material="steel")
    table = [[[k, q], [-q, k]] for k, q in zip(KXX, KXY, strict=True)]
    for name, node in (("a", 0), ("b", 2)):
        m.add_bearing(name, "s", node, table, CXX, speeds=speeds, interpolation=interp,
                      mass=0.2)  # fmt: skip
    m.add_bearing("axial", "s", 0, [1e7, 1e3], 0.0, components=["uz", "phiz"])
    return m


def _constant(W, m):
    """The same rotor with constant bearings equal to the tables at W."""
    c = Model()
    c.bodies = dict(m.bodies)
    for name in ("a", "b"):
        K, D, M = m.bearing_coefficients(name, W)
        c.add_bearing(name, "s", 0 if name == "a" else 2, K, D, components=None, mass=M)
    c.add_bearing("axial", "s", 0, [1e7, 1e3], 0.0, components=["uz", "phiz"])
    return c


@pytest.mark.parametrize(
    ("interp", "ref"),
    [("cubic", lambda x, y: make_interp_spline(x, y, k=3)),
     ("pchip", PchipInterpolator), ("linear", lambda x, y: make_interp_spline(x, y, k=1))],
)  # fmt: skip
def test_interpolation_is_scipy_and_ends_are_held(interp, ref):
    m = _rotor(interp)
    for W in (80.0, 222.0, 410.0):
        K, D, M = m.bearing_coefficients("a", W)
        assert np.isclose(K[0, 0], ref(SPEEDS, KXX)(W), rtol=1e-13)
        assert np.isclose(K[0, 1], ref(SPEEDS, KXY)(W), rtol=1e-13)
        assert np.isclose(K[1, 0], -ref(SPEEDS, KXY)(W), rtol=1e-13)
        assert np.isclose(D[1, 1], ref(SPEEDS, CXX)(W), rtol=1e-13)
        assert np.isclose(M[0, 0], 0.2, rtol=1e-14)
    assert np.isclose(m.bearing_coefficients("a", 10.0)[0][0, 0], KXX[0], rtol=1e-14)
    assert np.isclose(m.bearing_coefficients("a", 900.0)[0][0, 0], KXX[-1], rtol=1e-14)


def test_every_speed_path_uses_the_coefficients_at_that_speed():
    """template.assemble, lti_speeds and campbell give what a model rebuilt with constant
    bearings at each speed gives (the 'rebuild per speed by hand' of before)."""
    m = _rotor()
    m.add_force("f", "s", 1, force=(1.0, 0.0, 0.0), order=1)
    t = m.speed_template()
    speeds = [120.0, 260.0, 450.0]
    batch = lti_speeds(t, speeds)
    for i, W in enumerate(speeds):
        c = _constant(W, m)
        c.add_force("f", "s", 1, force=(1.0, 0.0, 0.0), order=1)
        a, b = t.assemble(W).system, c.assemble(W).system
        for X in "MDK":
            x, y = getattr(a, X)[0].toarray(), getattr(b, X)[0].toarray()
            assert np.abs(x - y).max() <= 1e-12 * np.abs(y).max()
        q = rl.solve(b, [1], method="lti", stability=False).harmonic(1)
        assert np.abs(batch.q[i, 0] - q).max() <= 1e-10 * np.abs(q).max()
    camp = campbell(m, speeds)
    for i, W in enumerate(speeds):
        ref = campbell(_constant(W, m), [W])
        n = min(6, ref.frequency.shape[1])
        assert np.allclose(camp.frequency[i, :n], ref.frequency[0, :n], rtol=1e-9)


def test_bad_tables_name_the_field():
    with pytest.raises(ModelError, match="stiffness"):
        _rotor(speeds=SPEEDS[:3])
    m = Model()
    m.add_shaft("s", [0.0, 0.3], outer_diameter=0.04, material="steel")
    with pytest.raises(ModelError, match="interpolation"):
        m.add_bearing("a", "s", 0, [1e6, 2e6], 0.0, speeds=[1.0, 2.0], interpolation="spline")
    with pytest.raises(ModelError, match="speeds"):
        m.add_bearing("b", "s", 0, [1e6, 2e6], 0.0, speeds=[2.0, 1.0])
