"""Modes of a rotor whose axial and torsional motion is free (no bearing holds uz or phiz):
the sparse shift-invert path is deterministic and, with the rigid-body modes recognised and
removed, agrees with the dense QZ solution of the same pencil."""

from __future__ import annotations

import numpy as np

from rheolin.data import example_text
from rheolin.io import parse_model
from rheolin.stability.modes import averaged_modes

LOCATING = """components = ["ux", "uy", "uz", "phiz"]
stiffness = ["5e7 N/m", "4e7 N/m", "5e7 N/m", "1e4 N*m/rad"]
damping = ["500 N*s/m", "500 N*s/m", "500 N*s/m", "1 N*m*s/rad"]"""
FREE = """stiffness = ["5e7 N/m", "4e7 N/m"]
damping = ["500 N*s/m", "500 N*s/m"]"""


def test_free_axial_and_torsional_rigid_modes_do_not_corrupt_the_elastic_modes():
    text = example_text("rotor")
    assert LOCATING in text
    system = parse_model(text.replace(LOCATING, FREE)).model.assemble(300.0).system
    dense = averaged_modes(system, 8, method="dense")
    first = averaged_modes(system, 8, method="sparse")
    again = averaged_modes(system, 8, method="sparse")
    assert np.array_equal(first.eigenvalues, again.eigenvalues)  # fixed starting vector
    assert first.rigid_eigenvalues >= 2  # axial translation and torsion: eigenvalue 0
    assert np.allclose(first.eigenvalues, dense.eigenvalues, rtol=1e-9, atol=0)
    assert dense.frequency[0] > 100.0  # no near-zero "mode" left
