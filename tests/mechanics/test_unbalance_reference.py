"""One unbalance-angle reference for every spin axis: angle 0 is a fixed global direction
projected onto the disk's plane (default x; y for a body turning about x), angles run
right-handed about the spin axis, and ``[model] unbalance_reference`` sets the direction.

The same rotor built along z and along x, both with the reference y: the unbalance points
along +y in both, so the unbalance responses are the same motion, rotated (a y displacement
equal in both; the 90-degree direction is z x y = -x in one and x x y = +z in the other)."""

from __future__ import annotations

import numpy as np
import pytest

from rheolin.errors import ModelError
from rheolin.mechanics import Model
from rheolin.mechanics.rigid import RigidNode, static_unbalance, unbalance_reference
from rheolin.results import solve_point


def _rotor(axis: tuple[float, float, float], reference: tuple[float, float, float] | None):
    m = Model(unbalance_reference=reference)
    m.add_shaft("r", np.linspace(0.0, 0.6, 4), outer_diameter=0.04, material="steel", axis=axis)
    m.add_disk("r", 1, outer_diameter=0.25, width=0.03, material="steel", unbalance=1e-4,
               unbalance_angle=np.radians(30.0))  # fmt: skip
    for node in (0, 3):
        lateral = ("ux", "uy") if axis == (0, 0, 1) else ("uy", "uz")  # bearings: global axes
        m.add_bearing(f"b{node}", "r", node, stiffness=2e7, damping=300.0, components=lateral)
    return m


def test_the_reference_is_one_global_direction_projected() -> None:
    assert unbalance_reference([0, 0, 1]).tolist() == [1.0, 0.0, 0.0]
    assert unbalance_reference([1, 0, 0]).tolist() == [0.0, 1.0, 0.0]  # along x: y
    tilted = unbalance_reference([0.6, 0.8, 0.0])  # x projected: (1,0,0) - 0.6 e
    np.testing.assert_allclose(tilted, np.array([0.64, -0.48, 0.0]) / 0.8, atol=1e-15)
    n = static_unbalance(RigidNode(2.0, [1, 1, 1]), 1e-3, np.pi / 2, axis=[1, 0, 0])
    np.testing.assert_allclose(n.com, [0.0, 0.0, 5e-4], atol=1e-18)  # x cross y = z
    with pytest.raises(ModelError, match="along the spin axis"):
        unbalance_reference([0, 1, 0], [0, 2, 0])


def test_same_rotor_along_z_and_x_responds_the_same_with_one_reference() -> None:
    W = 2500 * np.pi / 30
    pz = solve_point(_rotor((0, 0, 1), (0, 1, 0)), W, stability=False)
    px = solve_point(_rotor((1, 0, 0), (0, 1, 0)), W, stability=False)
    dz, dx = pz.assembled.dofs("r", 1), px.assembled.dofs("r", 1)
    qz, qx = pz.solution.harmonic(1), px.solution.harmonic(1)
    uz, ux = qz[dz[:3]], qx[dx[:3]]
    scale = np.abs(uz).max()
    assert scale > 0
    assert abs(uz[1] - ux[1]) < 1e-9 * scale  # y: the reference direction in both
    assert abs(-uz[0] - ux[2]) < 1e-9 * scale  # the 90-degree direction: -x and +z
    assert abs(uz[2]) < 1e-9 * scale and abs(ux[0]) < 1e-9 * scale  # no axial motion


def test_bad_reference_is_refused() -> None:
    with pytest.raises(ModelError, match="unbalance_reference"):
        Model(unbalance_reference=(0.0, 0.0, 0.0))
    m = Model(unbalance_reference=(0.0, 0.0, 1.0))
    m.add_shaft("r", [0.0, 0.5], outer_diameter=0.04, material="steel")
    with pytest.raises(ModelError, match="along the spin axis"):
        m.add_disk("r", 1, mass=1.0, inertia=[1, 1, 1], unbalance=1e-4)
