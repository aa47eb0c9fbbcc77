"""Bearings and forces at an offset from their node, against closed forms.

* A rigid body on two bearings at axial offsets ``+a`` and ``-b`` from its one node: the
  translation-tilt frequencies are those of ``k [[2, a - b], [a - b, a^2 + b^2]]`` against
  ``diag(m, I_d)`` (per plane), at standstill.
* A static force ``F x`` at an axial offset ``a``: the node deflects by ``F / k`` and tilts by
  ``a F / k_t`` (the moment ``r x F``).
* Bearings at offsets between two bodies, and the model file, round trip.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from rheolin.errors import ModelError
from rheolin.io import parse_model
from rheolin.mechanics import Model
from rheolin.results import solve_point
from rheolin.stability.modes import averaged_modes


def test_bearings_at_offsets_give_the_lever_closed_form() -> None:
    m_, Id, Ip, k, a, b = 30.0, 0.8, 0.3, 2e6, 0.25, 0.4
    model = Model()
    model.add_rigid_body("rotor", (0, 0, 0), m_, (Id, Id, Ip))
    model.add_bearing("A", "rotor", 0, stiffness=k, offset=[0.0, 0.0, a])
    model.add_bearing("B", "rotor", 0, stiffness=k, offset=[0.0, 0.0, -b])
    model.add_bearing("hold", "rotor", 0, [1e9, 1e9], components=["uz", "phiz"])
    s = model.assemble(1e-9).system  # standstill: no gyroscopic coupling
    got = np.sort(averaged_modes(s).frequency)
    K = k * np.array([[2.0, a - b], [a - b, a * a + b * b]])
    ref = np.sqrt(sla.eigh(K, np.diag([m_, Id]), eigvals_only=True))
    lateral = got[got < 1e3]  # the two planes; uz and phiz held stiffly far above
    np.testing.assert_allclose(lateral, np.repeat(ref, 2), rtol=1e-9)


def test_force_at_an_offset_carries_its_moment() -> None:
    F, a, k, kt = 150.0, 0.3, 1e7, 2e5
    model = Model()
    model.add_rigid_body("rotor", (0, 0, 0), 10.0, (0.1, 0.1, 0.2))
    model.add_bearing("b", "rotor", 0, [k, k, k, kt, kt, kt], components=None)
    model.add_force("f", "rotor", 0, force=[F, 0.0, 0.0], offset=[0.0, 0.0, a])
    p = solve_point(model, 100.0, stability=False)
    q0 = p.solution.harmonic(0).real
    np.testing.assert_allclose(q0[[0, 4]], [F / k, a * F / kt], rtol=1e-10)  # ux, phiy
    assert abs(q0[3]) < 1e-12 * a * F / kt


def test_offsets_in_the_model_file_round_trip_and_bad_ones_are_named() -> None:
    text = """
[model]
input_body = "r"
[[rigid_bodies]]
name = "r"
position = [0, 0, 0]
mass = "10 kg"
inertia = [0.1, 0.1, 0.2]
[[rigid_bodies.bearings]]
name = "b"
node = 0
components = "all"
stiffness = ["1e7 N/m", "1e7 N/m", "1e7 N/m", "2e5 N*m/rad", "2e5 N*m/rad", "2e5 N*m/rad"]
offset = ["0 mm", "0 mm", "300 mm"]
[[forces]]
name = "f"
body = "r"
node = 0
force = ["150 N", 0, 0]
offset = [0, 0, "300 mm"]
"""
    model = parse_model(text).model
    again = parse_model(model.to_toml()).model
    for m in (model, again):
        a = m.assemble(100.0).system
        np.testing.assert_allclose(a.K[0].toarray()[0, 4], 1e7 * 0.3, rtol=1e-12)  # ux-phiy
        np.testing.assert_allclose(a.f[0][4].real, 150 * 0.3, rtol=1e-12)
    with pytest.raises(ModelError, match=r"bearings\[0\]\.offset"):
        parse_model(text.replace('offset = ["0 mm", "0 mm", "300 mm"]', 'offset = ["1 mm"]'))
    m = Model()
    m.add_rigid_body("x", (0, 0, 0), 1.0, (1, 1, 1))
    with pytest.raises(ModelError, match="inertial frame"):
        m.add_bearing("b", "x", 0, 1e6, frame="x", offset=[0, 0, 0.1])
