"""Condensed bodies: files, frames and agreement with the beam path."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io

from rheolin.errors import ModelError
from rheolin.mechanics.beam import beam_body_matrices, beam_term
from rheolin.mechanics.condensed import CondensedBody, load_condensed
from rheolin.mechanics.rotation import rotate_body_matrix
from rheolin.mechanics.sections import Material, general_section, hollow_circular

MAT = Material(E=2.1e11, density=7800.0, nu=0.3, damping_beta=2e-5)
# body axes as columns in global coordinates: body z (the shaft axis) -> global x
FRAME = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
X = np.array([1.0, 0.0, 0.0])


def _body_matrices(section, n_el=2, L=0.6):
    """Assemble a shaft along body z from beam body matrices (body frame, not global)."""
    n = 6 * (n_el + 1)
    M, K, G = (np.zeros((n, n)) for _ in range(3))
    for i in range(n_el):
        b = beam_body_matrices(L / n_el, section, MAT, [0, 0, 1], rotary="consistent")
        sl = slice(6 * i, 6 * i + 12)
        M[sl, sl] += b.M
        K[sl, sl] += b.K
        G[sl, sl] += b.gyroscopic
    return M, K, G


def _beam_path(section, s, w1, n_el=2, L=0.6, rotary="consistent"):
    n = 6 * (n_el + 1)
    out = {}
    for i in range(n_el):
        t = beam_term(
            (i + 3, i + 4), L / n_el, section, MAT, X, X, s, w1, y_axis=[0, 1, 0], rotary=rotary
        )
        for name in "MDK":
            for k, v in getattr(t, name).items():
                out.setdefault((name, k), np.zeros((n, n), dtype=complex))
                out[(name, k)][6 * i : 6 * i + 12, 6 * i : 6 * i + 12] += v
    return out


def test_condensed_from_files_matches_beam_path(tmp_path):
    sec = hollow_circular(0.05, 0.02)
    M, K, G = _body_matrices(sec)
    scipy.io.mmwrite(str(tmp_path / "M.mtx"), M)
    scipy.io.mmwrite(str(tmp_path / "K.mtx"), K)
    np.save(tmp_path / "G.npy", G)
    np.save(tmp_path / "D.npy", MAT.damping_beta * K)
    body = load_condensed(
        M=tmp_path / "M.mtx",
        K=tmp_path / "K.mtx",
        G=tmp_path / "G.npy",
        D=tmp_path / "D.npy",
        nodes=[3, 4, 5],
        frame=FRAME,
    )
    np.savez(
        tmp_path / "b.npz", M=M, K=K, G=G, D=MAT.damping_beta * K, nodes=[3, 4, 5], frame=FRAME
    )
    body_npz = load_condensed(tmp_path / "b.npz")
    w1 = 900.0
    ref = _beam_path(sec, 2, w1)
    for b in (body, body_npz):
        t = b.term(X, 2, w1)
        assert t.dofs.tolist() == list(range(18, 36))
        got = {(name, k): v for name in "MDK" for k, v in getattr(t, name).items()}
        assert set(got) == set(ref)
        for key, v in ref.items():
            scale = np.abs(v).max() + 1e-300
            assert np.abs(got[key] - v).max() <= 1e-11 * scale, key


def test_non_axisymmetric_stiffness_in_a_rotated_frame():
    # flat shaft: K(t) = Rt K_B Rt^T must match the beam built directly in global axes
    sec = general_section(1e-3, 2e-7, 0.5e-7, 1.5e-7)
    Kb = beam_body_matrices(0.3, sec, MAT, [0, 0, 1]).K
    body = CondensedBody(M=np.eye(12), K=Kb, nodes=[0, 1], frame=FRAME)
    t = body.term(X, 1, 50.0)
    ref = beam_term((0, 1), 0.3, sec, MAT, X, X, 1, 50.0, y_axis=[0, 1, 0]).K
    circ = beam_term(
        (0, 1), 0.3, sec, Material(2.1e11, 7800.0, nu=0.3), X, X, 1, 50.0, y_axis=[0, 1, 0]
    ).K
    assert sorted(t.K) == sorted(ref) == [-2, 0, 2]
    for k in (0, 2):
        np.testing.assert_allclose(t.K[k], circ[k], atol=1e-9 * np.abs(circ[0]).max())
    # the body-frame stiffness seen at t = pi / (2 W): rotated a quarter turn about global x
    tq = np.pi / 100.0
    Kt = sum(np.real(v * np.exp(1j * k * 50.0 * tq)) for k, v in t.K.items())
    Rq = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])
    Tb = np.kron(np.eye(4), Rq @ FRAME)
    np.testing.assert_allclose(Kt, Tb @ Kb @ Tb.T, atol=1e-9 * np.abs(Kb).max())
    assert sorted(rotate_body_matrix(np.eye(12), X, 1)) == [0]


def test_bad_input():
    with pytest.raises(ModelError, match="12x12"):
        CondensedBody(M=np.eye(6), K=np.eye(12), nodes=[0, 1])
    with pytest.raises(ModelError, match="frame"):
        CondensedBody(M=np.eye(6), K=np.eye(6), nodes=[0], frame=2 * np.eye(3))
    with pytest.raises(ModelError, match="nodes"):
        CondensedBody(M=np.eye(12), K=np.eye(12), nodes=[1, 1])
    with pytest.raises(ModelError, match="npz"):
        load_condensed("body.txt")
