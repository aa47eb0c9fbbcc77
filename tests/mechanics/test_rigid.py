"""Rigid node: closed forms and a full nonlinear Newton–Euler simulation
(docs/rotating-bodies.md)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import rheolin as rl
from rheolin.errors import ModelError
from rheolin.mechanics.rigid import (
    RigidNode,
    couple_unbalance,
    disk,
    rigid_node_coefficients,
    static_unbalance,
)
from rheolin.mechanics.rotation import skew


def test_axisymmetric_disk_gives_classic_gyroscopic_coupling():
    e = np.array([1.0, 2.0, 2.0]) / 3.0
    Jd, Jp, W = 0.3, 0.5, 40.0
    J = Jd * np.eye(3) + (Jp - Jd) * np.outer(e, e)
    M, D, K, f = rigid_node_coefficients(7.0, J, np.zeros(3), e, 2, W / 2)
    assert sorted(M) == sorted(D) == [0]
    np.testing.assert_allclose(D[0][3:, 3:], -W * Jp * skew(e), atol=1e-12)
    np.testing.assert_allclose(D[0][:3], 0.0, atol=1e-12)
    np.testing.assert_allclose(M[0], np.diag([7.0] * 3 + [0] * 3) + np.pad(J, ((3, 0), (3, 0))))
    assert np.abs(K[0]).max() < 1e-12 and np.abs(f[0]).max() < 1e-12


def test_static_unbalance_force_is_centrifugal():
    # force on the node from an offset centre of mass: m e W^2 rotating with the body
    m, U, W = 4.0, 2e-3, 30.0
    node = static_unbalance(RigidNode(m, [1.0, 1.0, 1.5]), U, angle=0.3)
    _, _, _, f = node.coefficients([0, 0, 1], 1, W)
    t = np.linspace(0, 0.2, 7)
    force = sum(np.real(fk[:3, None] * np.exp(1j * k * W * t)) for k, fk in f.items())
    expected = U * W**2 * np.array([np.cos(W * t + 0.3), np.sin(W * t + 0.3), 0 * t])
    np.testing.assert_allclose(force, expected, atol=1e-12)


def test_couple_unbalance_moment_closed_form():
    # principal axes tilted: moment -W J' e = W^2 U_c (rotating radial direction x e)
    W, Uc = 25.0, 1e-3
    node = couple_unbalance(RigidNode(1.0, [0.2, 0.2, 0.3]), Uc)
    _, _, _, f = node.coefficients([0, 0, 1], 1, W)
    t = np.linspace(0, 0.3, 5)
    mom = sum(np.real(fk[3:, None] * np.exp(1j * k * W * t)) for k, fk in f.items())
    # J e = Jp e - Uc a(t), a = (cos Wt, sin Wt, 0): -W J' e = W Uc a' = W^2 Uc (-sin, cos, 0)
    expected = W**2 * Uc * np.array([-np.sin(W * t), np.cos(W * t), 0 * t])
    np.testing.assert_allclose(mom, expected, atol=1e-12)


def test_disk_geometry_closed_form():
    node = disk(0.3, 0.05, 7800.0, inner_diameter=0.1, axis=[1, 0, 0])
    m = 7800.0 * np.pi * (0.3**2 - 0.1**2) / 4 * 0.05
    assert node.mass == pytest.approx(m, rel=1e-14)
    assert node.inertia[0, 0] == pytest.approx(m * (0.15**2 + 0.05**2) / 2, rel=1e-14)
    assert node.inertia[1, 1] == pytest.approx(m * (3 * (0.15**2 + 0.05**2) + 0.05**2) / 12)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"mass": -1.0, "inertia": np.eye(3)}, "mass"),
        ({"mass": 1.0, "inertia": np.ones((2, 2))}, "inertia"),
        ({"mass": 1.0, "inertia": np.triu(np.ones((3, 3)))}, "symmetric"),
        ({"mass": 1.0, "inertia": np.eye(3), "com": [1, 2]}, "com"),
    ],
)
def test_bad_input_raises(kwargs, match):
    with pytest.raises(ModelError, match=match):
        RigidNode(**kwargs)
    with pytest.raises(ValueError, match="axis"):
        RigidNode(1.0, np.eye(3)).term(0, [0, 0, 0], 1, 1.0)


# --------------------------------------------------------------------------------------------
# Nonlinear rigid-body simulation against the linear harmonic-balance steady state
# --------------------------------------------------------------------------------------------

W = 50.0  # spin speed [rad/s], s = 1, w1 = W
MASS = 3.0
E_AXIS = np.array([0.0, 0.0, 1.0])
KU = np.array([[1.0e5, 1.0e4, 0.0], [1.0e4, 1.3e5, 0.0], [0.0, 0.0, 2.0e5]])
KP = np.array([[2.0e3, 0.0, 1.0e2], [0.0, 2.5e3, 0.0], [1.0e2, 0.0, 1.0e3]])
CU = 0.1 * 2 * np.sqrt(1.2e5 * MASS) * np.eye(3)
CP = np.diag([3.0, 3.0, 2.0])


def _body(a: float) -> tuple[np.ndarray, np.ndarray]:
    """Anisotropic, non-principal inertia and CoM offset; unbalance scaled by ``a``."""
    J = np.array([[0.05, 0.004, 0.0], [0.004, 0.07, 0.0], [0.0, 0.0, 0.1]])
    J = J + a * np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -0.6], [1.0, -0.6, 0.0]])
    c = a * np.array([0.4, -0.25, 0.15])
    return J, c


def _linear_steady_state(J, c, n_harm):
    M, D, K, f = rigid_node_coefficients(MASS, J, c, E_AXIS, 1, W)
    K = dict(K)
    D = dict(D)
    K[0] = K[0] + np.block([[KU, np.zeros((3, 3))], [np.zeros((3, 3)), KP]])
    D[0] = D[0] + np.block([[CU, np.zeros((3, 3))], [np.zeros((3, 3)), CP]])
    system = rl.PeriodicSystem(omega=W, M=M, D=D, K=K, f=f)
    sol = rl.solve(system, rl.HarmonicSet.full(n_harm), method="auto", rtol=1e-13)
    assert sol.success
    return sol


def _rotvec_matrix(p: np.ndarray) -> np.ndarray:
    th = np.linalg.norm(p)
    S = skew(p)
    if th < 1e-8:
        return np.eye(3) + S + 0.5 * S @ S
    return np.eye(3) + np.sin(th) / th * S + (1 - np.cos(th)) / th**2 * S @ S


def _quat_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _log(Q: np.ndarray) -> np.ndarray:
    """Rotation vector of a rotation matrix close to the identity."""
    v = 0.5 * np.array([Q[2, 1] - Q[1, 2], Q[0, 2] - Q[2, 0], Q[1, 0] - Q[0, 1]])
    s = np.linalg.norm(v)
    c = 0.5 * (np.trace(Q) - 1.0)
    return v if s == 0.0 else v * np.arctan2(s, c) / s


def _nonlinear_rhs(J_B, c_B):
    """Newton–Euler of the spinning rigid body, orientation as a quaternion, no linearization."""

    def rhs(t, y):
        u, v, quat, w = y[:3], y[3:6], y[6:10], y[10:13]
        R = _quat_matrix(quat)
        Q = R @ _rotvec_matrix(W * t * E_AXIS).T
        phi = _log(Q)
        w_rel = w - W * (Q @ E_AXIS)  # angular velocity relative to the reference rotation
        F = -KU @ u - CU @ v
        T = -KP @ phi - CP @ w_rel
        r = R @ c_B
        Jg = R @ J_B @ R.T
        alpha = np.linalg.solve(Jg, T - np.cross(r, F) - np.cross(w, Jg @ w))
        a = F / MASS - np.cross(alpha, r) - np.cross(w, np.cross(w, r))
        qw, qv = quat[0], quat[1:]
        dq = 0.5 * np.concatenate([[-w @ qv], qw * w + np.cross(w, qv)])
        return np.concatenate([v, a, dq, alpha])

    return rhs


def _compare(a: float, n_periods: int = 5) -> dict[str, float]:
    """Relative errors (u, phi) over the last period against the nonlinear simulation."""
    J, c = _body(a)
    M, D, K, f = rigid_node_coefficients(MASS, J, c, E_AXIS, 1, W)
    springs = np.block([[KU, np.zeros((3, 3))], [np.zeros((3, 3)), KP]])
    dampers = np.block([[CU, np.zeros((3, 3))], [np.zeros((3, 3)), CP]])
    D = {**D, 0: D[0] + dampers}
    full = {**K, 0: K[0] + springs}
    no_k_rows = {0: springs}  # the model without its K rows, for contrast only
    H = rl.HarmonicSet.full(25)
    sols = [
        rl.solve(rl.PeriodicSystem(omega=W, M=M, D=D, K=KK, f=f), H, rtol=1e-13)
        for KK in (full, no_k_rows)
    ]
    assert all(s.success for s in sols)
    sol = sols[0]
    n = sol.harmonics
    q0 = np.real(sol.q.sum(axis=0))
    dq0 = np.real((1j * n[:, None] * W * sol.q).sum(axis=0))
    w0 = dq0[3:] + W * E_AXIS + W * np.cross(q0[3:], E_AXIS)  # omega = phi' + W (I + [phi]x) e
    y0 = np.concatenate([q0[:3], dq0[:3], _rotvec_quat(q0[3:]), w0])
    period = 2 * np.pi / W
    t_end = n_periods * period
    t_eval = np.linspace(t_end - period, t_end, 48)
    with np.errstate(under="ignore"):  # SciPy's step-size logic may underflow harmlessly
        res = solve_ivp(
            _nonlinear_rhs(J, c),
            (0, t_end),
            y0,
            method="DOP853",
            rtol=1e-10,
            atol=1e-13,
            t_eval=t_eval,
        )
    assert res.success
    u_nl = res.y[:3].T
    phi_nl = np.array(
        [
            _log(_quat_matrix(qq) @ _rotvec_matrix(W * t * E_AXIS).T)
            for qq, t in zip(res.y[6:10].T, t_eval, strict=True)
        ]
    )
    out = {}
    for name, s in zip(("full", "no_k"), sols, strict=True):
        lin = s.evaluate(t_eval)
        out[f"u_{name}"] = np.abs(u_nl - lin[:, :3]).max() / np.abs(lin[:, :3]).max()
        out[f"phi_{name}"] = np.abs(phi_nl - lin[:, 3:]).max() / np.abs(lin[:, 3:]).max()
    out["amplitude"] = float(np.abs(sols[0].evaluate(t_eval)[:, 3:]).max())
    return out


def _rotvec_quat(p: np.ndarray) -> np.ndarray:
    th = np.linalg.norm(p)
    return np.concatenate([[np.cos(th / 2)], np.sinc(th / (2 * np.pi)) * p / 2])


def test_nonlinear_rigid_body_matches_linear_steady_state():
    small, large = _compare(2e-3), _compare(4e-3)
    # linearization error only: small, and shrinking with the amplitude (phi ~ a, u ~ a^2)
    assert large["amplitude"] == pytest.approx(2 * small["amplitude"], rel=0.05)
    assert small["u_full"] < 5e-5 and small["phi_full"] < 1.5e-3
    assert 1.6 < large["phi_full"] / small["phi_full"] < 2.4
    assert 1.6 < large["u_full"] / small["u_full"] < 4.8
    # contrast: the same model without its K rows is far off
    assert small["u_no_k"] > 30 * small["u_full"]
