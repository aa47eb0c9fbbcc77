"""Condensed bodies at model level, against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

import rheolin as rl


def _spinning_disk_model(speed_ratio: int = 1) -> rl.Model:
    """One condensed rigid node: mass m, inertia (Jt, Jt, Jp), gyroscopic G per unit speed."""
    m, jt, jp = 2.0, 0.01, 0.02
    M = np.diag([m, m, m, jt, jt, jp])
    G = np.zeros((6, 6))
    G[3, 4], G[4, 3] = jp, -jp  # G = -Jp [e]x on the rotations, e = z: D = W G
    model = rl.Model()
    model.add_condensed_body("disk", [[0, 0, 0]], M=M, K=np.zeros((6, 6)), G=G)
    return model


def test_condensed_mass_on_springs_has_the_closed_form_frequencies() -> None:
    """Translational sqrt(k/m) and tilting forward/backward whirl of a spinning disk."""
    k, kr = 4e5, 2e3
    m, jt, jp = 2.0, 0.01, 0.02
    model = _spinning_disk_model()
    stiff = np.diag([k, k, k, kr, kr, 1e3])
    model.add_bearing("support", "disk", 0, stiffness=stiff, components=None)
    W = 300.0
    system = model.assemble(W).system
    M = system.M[0].toarray()
    K = system.K[0].toarray()
    D = system.D[0].toarray() if 0 in system.D else np.zeros_like(M)
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, D)]])
    freqs = np.sort(np.abs(np.linalg.eigvals(A).imag))[::2]
    # closed forms: translations sqrt(k/m); tilt whirl roots of Jt w^2 -+ Jp W w - kr = 0
    tilt = [
        (-jp * W + np.sqrt((jp * W) ** 2 + 4 * jt * kr)) / (2 * jt),
        (jp * W + np.sqrt((jp * W) ** 2 + 4 * jt * kr)) / (2 * jt),
    ]
    expected = np.sort([np.sqrt(k / m)] * 3 + tilt + [np.sqrt(1e3 / jp)])
    np.testing.assert_allclose(freqs, expected, rtol=1e-9)


def test_condensed_body_from_npz(tmp_path) -> None:
    path = tmp_path / "body.npz"
    np.savez(path, M=np.eye(6), K=np.eye(6))
    model = rl.Model()
    model.add_condensed_body("b", [[0, 0, 0]], path=str(path))
    system = model.assemble(10.0).system
    np.testing.assert_allclose(system.K[0].toarray(), np.eye(6))
    with pytest.raises(rl.ModelError, match="`M` and `K`"):
        rl.Model().add_condensed_body("c", [[0, 0, 0]], M=np.eye(6))
