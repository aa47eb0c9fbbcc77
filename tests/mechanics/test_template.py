"""The model assembled once for every speed (``SpeedTemplate``): each element's polynomial in
``w1`` against its coefficients computed directly at that ``w1``, and one template reused over
speeds against the closed-form unbalance response."""

from __future__ import annotations

import numpy as np
import pytest

import rheolin as rl
from rheolin.mechanics import Model
from rheolin.mechanics.beam import beam_body_matrices, beam_speed_term
from rheolin.mechanics.rigid import RigidNode, rigid_node_coefficients
from rheolin.mechanics.rotation import add_series, circulatory_matrix, rotate_body_matrix
from rheolin.mechanics.sections import Material, general_section


@pytest.fixture(autouse=True)
def _allow_underflow():
    with np.errstate(under="ignore"):
        yield


def _close(a: dict, b: dict, rtol: float = 1e-13) -> None:
    scale = max(float(np.abs(v).max()) for v in b.values())
    for k in set(a) | set(b):
        x = a.get(k, 0.0)
        y = b.get(k, 0.0)
        assert np.abs(np.asarray(x) - np.asarray(y)).max() <= rtol * scale, k


@pytest.mark.parametrize("w1", [0.3, 120.0, 4e3])
def test_rigid_node_polynomial_is_its_coefficients_at_w1(w1):
    """Unbalanced, non-principal rigid node spinning at 2 w1: M constant, D linear, K and f
    quadratic in w1 reproduce the exact linearization evaluated at w1."""
    J = np.array([[0.3, 0.01, -0.02], [0.01, 0.25, 0.015], [-0.02, 0.015, 0.5]])
    node = RigidNode(4.0, J, com=[2e-3, -1e-3, 5e-4])
    axis = np.array([0.2, 0.1, 1.0])
    direct = rigid_node_coefficients(4.0, J, node.com, axis, 2, w1)
    at = node.speed_term(3, axis, 2).at(w1)
    for got, ref in zip((at.M, at.D, at.K, at.f), direct, strict=True):
        _close(got, ref)


@pytest.mark.parametrize("w1", [0.5, 300.0])
def test_beam_polynomial_is_the_rotating_element_at_w1(w1):
    """A non-axisymmetric damped shaft element (lumped rotary inertia): ``Rt K_B Rt^T`` plus the
    circulatory stiffness and the rigid-node rows, each computed at w1."""
    sec = general_section(1e-3, 2e-7, 1e-7, 3e-7, 0.8, 0.8)
    mat = Material(2e11, 7800.0, nu=0.3, damping_beta=1e-4)
    e = np.array([0.0, 0.0, 1.0])
    b = beam_body_matrices(0.2, sec, mat, e)
    assert b.node_inertia is not None
    Mr, Dr, Kr, _ = rigid_node_coefficients(0.0, b.node_inertia, np.zeros(3), e, 1, w1)

    def both_nodes(series: dict) -> dict:
        out: dict = {}
        for off in (0, 6):
            pad = {k: np.pad(v, ((off, 6 - off), (off, 6 - off))) for k, v in series.items()}
            out = add_series(out, pad)
        return out

    K = add_series(rotate_body_matrix(b.K, e, 1), circulatory_matrix(b.D, e, 1, w1), both_nodes(Kr))
    D = add_series(rotate_body_matrix(b.D, e, 1), both_nodes(Dr))
    M = add_series(rotate_body_matrix(b.M, e, 1), both_nodes(Mr))
    at = beam_speed_term((0, 1), b, e, 1).at(w1)
    assert sorted(at.K) == [-2, 0, 2]
    _close(at.K, K)
    _close(at.D, D)
    _close(at.M, M)


def test_one_template_over_speeds_gives_the_closed_form_unbalance_response():
    """Rigid rotor (m, k, c, U) assembled once: orbit radius ``U W^2 / |k - m W^2 + i c W|``
    at every speed below, near and above the critical speed."""
    m, k, c, U = 10.0, 1e6, 300.0, 2e-4
    model = Model()
    model.add_rigid_body("rotor", (0, 0, 0), m, (0.01, 0.01, 0.02))
    model.add_disk("rotor", 0, unbalance=U)
    model.add_bearing("radial", "rotor", 0, k, c, components=("ux", "uy"))
    model.add_bearing(
        "rest", "rotor", 0, [1e7, 1e5, 1e5, 1e3], 10.0, components=("uz", "phix", "phiy", "phiz")
    )
    template = model.speed_template()
    for W in (50.0, 310.0, 316.0, 900.0):
        a = template.assemble(W)
        assert a.speed == W and a.omega == W
        sol = rl.solve(a.system, rl.HarmonicSet.closure(a.system, order=2))
        assert sol.success
        X = U * W**2 / abs(k - m * W**2 + 1j * c * W)
        q = sol.harmonic(1)[a.dofs("rotor", 0)]
        assert 2 * abs(q[0]) == pytest.approx(X, rel=1e-9)
        assert 2 * abs(q[1]) == pytest.approx(X, rel=1e-9)
