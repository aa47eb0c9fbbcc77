"""A disk whose centre of mass sits axially off its node (``axial_offset``): the node carries
the lever arm exactly. Against the closed form of a rigid disk on a translational spring ``k``
and a tilting spring ``kr`` at the node: per plane ``M = [[m, m d], [m d, Jd + m d^2]]``,
``K = diag(k, kr)``; and the model file's ``axial_offset`` gives the same matrices."""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

import rheolin as rl
from rheolin.io import parse_model
from rheolin.stability.modes import averaged_modes

M, JD, JP, D = 4.0, 0.02, 0.03, 0.05
K, KR = 2e6, 5e4


def _model() -> rl.Model:
    model = rl.Model(input_body="r")
    model.add_rigid_body("r", (0.0, 0.0, 0.0), M, (JD, JD, JP))
    model.add_disk("r", 0, axial_offset=D)  # the rigid body's own mass, off its node
    model.add_bearing("b", "r", 0, [K, K, 1e9, KR, KR, 1e5], 0.0,
                      ("ux", "uy", "uz", "phix", "phiy", "phiz"))  # fmt: skip
    return model


def test_axial_offset_couples_translation_and_tilt_as_the_closed_form():
    system = _model().assemble(1e-7).system  # standstill in effect: no gyroscopic coupling
    f = np.sort(averaged_modes(system, 10, method="dense").frequency)  # rad/s
    Mp = np.array([[M, M * D], [M * D, JD + M * D * D]])
    w = np.sqrt(sla.eigh(np.diag([K, KR]), Mp, eigvals_only=True))
    want = np.sort(np.concatenate([w, w]))  # two planes
    assert np.allclose(f[:4], want, rtol=1e-9), (f[:4], want)


def test_model_file_axial_offset_gives_the_same_matrices():
    text = """
[model]
input_body = "r"
[[rigid_bodies]]
name = "r"
position = "0 0 0 m"
mass = "4 kg"
inertia = ["0.02 kg*m^2", "0.02 kg*m^2", "0.03 kg*m^2"]
[[rigid_bodies.disks]]
node = 0
axial_offset = "50 mm"
[[rigid_bodies.bearings]]
name = "b"
node = 0
components = "all"
stiffness = ["2e6 N/m", "2e6 N/m", "1e9 N/m", "5e4 N*m/rad", "5e4 N*m/rad", "1e5 N*m/rad"]
"""
    a = parse_model(text).model.assemble(10.0).system
    b = _model().assemble(10.0).system
    for name in "MDK":
        for k, x in getattr(b, name).items():
            y = getattr(a, name)[k]
            x = x.toarray() if hasattr(x, "toarray") else x
            y = y.toarray() if hasattr(y, "toarray") else y
            assert np.allclose(x, y, rtol=1e-12, atol=1e-12 * np.abs(x).max()), (name, k)
