"""Conical (tapered) and layered shaft elements."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from rheolin.mechanics.beam import beam_body_matrices
from rheolin.mechanics.conical import conical_body_matrices, conical_local_matrices
from rheolin.mechanics.sections import Material, hollow_circular

E, G, RHO = 211e9, 81.2e9, 7810.0


def test_uniform_limit_equals_the_timoshenko_element():
    """Two independent derivations: the conical closed form at zero taper and the uniform
    Timoshenko element of rheolin.mechanics.beam (Friedman & Kosmatka mass)."""
    mat = Material(E, RHO, G=G)
    for axis in ([0, 0, 1], [1, 0, 0], [0.3, -0.5, 0.8]):
        a = conical_body_matrices(0.25, (0.05, 0.01, 0.05, 0.01), E, G, RHO, axis)
        b = beam_body_matrices(0.25, hollow_circular(0.05, 0.01, mat.nu), mat, axis)
        for x, y in ((a.M, b.M), (a.K, b.K), (a.gyroscopic, b.gyroscopic)):
            assert np.abs(x - y).max() <= 1e-15 * np.abs(y).max()


def test_tapered_mass_is_the_frustum_mass():
    """Translational mass of a solid frustum: rho pi L (R^2 + R r + r^2) / 3."""
    L, D1, D2 = 0.3, 0.08, 0.04
    M, _, _ = conical_local_matrices(L, D1, 0.0, D2, 0.0, E, G, RHO)
    frustum = RHO * np.pi * L * ((D1 / 2) ** 2 + D1 * D2 / 4 + (D2 / 2) ** 2) / 3
    assert np.isclose(M[np.ix_([0, 6], [0, 6])].sum(), frustum, rtol=1e-13)
    assert np.isclose(M[np.ix_([1, 7], [1, 7])].sum(), frustum, rtol=1e-13)


def test_tapered_element_matches_ross():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rs = pytest.importorskip("ross")
        from ross.materials import Material as RossMaterial
    el = rs.ShaftElement(L=0.3, idl=0.01, odl=0.06, idr=0.02, odr=0.04,
                         material=RossMaterial(name="m", rho=RHO, E=E, G_s=G))  # fmt: skip
    M, K, Gy = conical_local_matrices(0.3, 0.06, 0.01, 0.04, 0.02, E, G, RHO)
    for x, y in ((M, el.M()), (K, el.K()), (Gy, el.G())):
        assert np.abs(x - y).max() <= 1e-14 * np.abs(y).max()
