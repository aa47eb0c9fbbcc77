"""Joints against closed forms: bearings fixed in space and springs in a rotating body's axes."""

from __future__ import annotations

import numpy as np
import pytest

import rheolin as rl
from rheolin.errors import ModelError
from rheolin.mechanics.joints import coupling_term, expand_matrix, joint_term
from rheolin.mechanics.model import Model

STIFF = 1e6  # tilt and torsion supports (removed by rigid constraints where noted)


@pytest.fixture(autouse=True)
def _allow_underflow():
    """Hill eigenvectors have negligibly small far harmonics; underflow there is harmless."""
    with np.errstate(under="ignore"):
        yield


def test_cross_coupled_bearing_harmonic_force_real_arithmetic():
    """Mass on an anisotropic, cross-coupled bearing, F cos(w t + phase) along x.

    Reference: x(t) = A cos wt + B sin wt solved in real arithmetic (4x4)."""
    m, W = 3.0, 150.0
    K = np.array([[2e5, 4e4], [-3e4, 5e5]])
    C = np.array([[80.0, 10.0], [10.0, 120.0]])
    F, phase, order = 40.0, 0.3, 2
    model = Model()
    model.add_rigid_body("mass", (0, 0, 0), m, (1.0, 1.0, 1.0))
    model.add_bearing("radial", "mass", 0, K, C, components=("ux", "uy"))
    model.add_bearing("rest", "mass", 0, 1e6, 1.0, components=("uz", "phix", "phiy", "phiz"))
    model.add_force("f", "mass", 0, force=(F, 0, 0), order=order, phase=phase)
    a = model.assemble(W)
    sol = rl.solve(a.system, rl.HarmonicSet([a.plan.harmonic(order)]))
    assert sol.success
    w = order * W
    # [K - m w^2, w C; -w C, K - m w^2] [A; B] = [F cos(phase) e_x; -F sin(phase) e_x]
    Kd = K - m * w**2 * np.eye(2)
    big = np.block([[Kd, w * C], [-w * C, Kd]])
    AB = np.linalg.solve(big, [F * np.cos(phase), 0, -F * np.sin(phase), 0])
    t = np.linspace(0, 2 * np.pi / w, 7)
    ref = np.outer(np.cos(w * t), AB[:2]) + np.outer(np.sin(w * t), AB[2:])
    got = sol.evaluate(t)[:, :2]
    assert np.allclose(got, ref, rtol=0, atol=1e-10 * np.abs(ref).max())


@pytest.mark.parametrize("W", [40.0, 75.0, 120.0])
def test_rotating_frame_spring_is_the_asymmetric_jeffcott_rotor(W):
    """Unbalanced rigid rotor on a spring defined in its own axes (k_x != k_y) with stationary
    damping c: z = x + i y = P exp(iWt), docs/solvers.md, reference cases closed form."""
    m, kx, ky, c, U, beta = 2.0, 4e3, 1.6e4, 15.0, 2e-4, 0.4
    model = Model()
    model.add_rigid_body("rotor", (0, 0, 0), m, (1e-3, 1e-3, 2e-3))
    model.add_disk("rotor", 0, unbalance=U, unbalance_angle=beta)
    model.add_bearing("shaft", "rotor", 0, [kx, ky], components=("ux", "uy"), frame="rotor")
    model.add_bearing("support", "rotor", 0, STIFF, 0.0, components=("uz", "phix", "phiy", "phiz"))
    model.add_bearing("damper", "rotor", 0, 0.0, c, components=("ux", "uy"))
    a = model.assemble(W)
    assert a.omega == W and a.plan.spin["rotor"] == 1
    # rigid constraints on uz and the rotations: keep the rows/columns of ux, uy
    keep = [0, 1]

    def sub(table):
        return {k: v.toarray()[np.ix_(keep, keep)] for k, v in table.items()}

    system = rl.PeriodicSystem(
        a.omega,
        M=sub(a.system.M),
        D=sub(a.system.D),
        K=sub(a.system.K),
        f={k: v[keep] for k, v in a.system.f.items()},
    )
    H = rl.HarmonicSet.closure(system, order=4)
    sol = rl.solve(system, H, method="direct", stability=False)
    assert sol.residual < 1e-10
    e = U / m
    lhs = np.array([[kx - m * W**2, -c * W], [c * W, ky - m * W**2]])
    re_p, im_p = np.linalg.solve(lhs, m * e * W**2 * np.array([np.cos(beta), np.sin(beta)]))
    P = re_p + 1j * im_p
    q1 = sol.harmonic(1)
    assert abs(2 * q1[0] - P) < 1e-8 * abs(P)
    assert abs(2 * q1[1] + 1j * P) < 1e-8 * abs(P)
    # the exact response has no other harmonic in x, y
    others = [n for n in sol.harmonics if abs(n) != 1]
    assert max(np.abs(sol.harmonic(n)[:2]).max() for n in others) < 1e-8 * abs(P)
    unstable = (kx - m * W**2) * (ky - m * W**2) + c**2 * W**2 < 0
    assert rl.floquet(system, 6).stable == (not unstable)


def test_rotating_damping_gives_circulatory_stiffness():
    """Isotropic damping c_r in a frame spinning at W: K gains c_r W [[0, 1], [-1, 0]] (the
    rotating-damping force c_r (v - W e x u) in inertial axes)."""
    cr, W = 7.0, 30.0
    t = coupling_term(range(6), None, damping=expand_matrix(cr, ("ux", "uy")), spin=2, omega=W / 2)
    assert set(t.K) == {0}
    assert np.allclose(t.K[0][:2, :2], cr * W * np.array([[0, 1], [-1, 0]]))
    assert np.allclose(t.D[0][:2, :2], cr * np.eye(2))


def test_node_to_node_joint_and_errors():
    t = joint_term(range(6), range(6, 12), stiffness=expand_matrix([1.0, 2.0], ("uz", "phiz")))
    assert t.K[0][2, 8] == -1.0 and t.K[0][11, 11] == 2.0 and t.K[0][5, 11] == -2.0
    with pytest.raises(ModelError, match="components"):
        expand_matrix(1.0, ("ux", "wz"))
    with pytest.raises(ModelError, match="stiffness"):
        expand_matrix([[1.0, 2.0]], ("ux", "uy"))
    model = Model()
    model.add_rigid_body("a", (0, 0, 0), 1.0, (1, 1, 1))
    with pytest.raises(ModelError, match="frame"):
        model.add_bearing("b", "a", 0, 1.0, frame="nope")
    with pytest.raises(ModelError, match="node"):
        model.add_bearing("b", "a", 3, 1.0)
