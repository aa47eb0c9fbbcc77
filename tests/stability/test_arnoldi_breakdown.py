import importlib

import numpy as np
import scipy.linalg as sla


def test_arnoldi_accepts_only_converged_ritz_pairs_at_a_breakdown() -> None:
    """A shift on an exponent (a tracked start: within 1e-15 of it, relative) makes its Ritz value
    huge, so the Krylov space looks exhausted relative to it after two steps, while the
    far Ritz pairs are not converged at all (the gearbox once reported a false +8135 1/s
    exponent so). Every pair ``arnoldi`` accepts must be one: its true residual is checked
    on the operator."""
    se = importlib.import_module("rheolin.floquet.shift_invert")
    rng = np.random.default_rng(7)
    n = 120
    lam = -rng.uniform(1e2, 1e4, n) + 1j * rng.uniform(-1e5, 1e5, n)
    V = np.eye(n) + 0.3 * (rng.standard_normal((n, n)) + 1j * rng.standard_normal((n, n)))
    A = V @ np.diag(lam) @ np.linalg.inv(V)
    sigma = lam[0] + 1e-15 * abs(lam[0]) * (1 + 1j)
    lu = sla.lu_factor(A - sigma * np.eye(n))

    def apply(y: np.ndarray) -> np.ndarray:
        return sla.lu_solve(lu, y)

    for weights in ([1.0, 1e-2, 1e-2], [1.0, 1.0, 1e-3], [1.0, 0.3, 0.3, 0.3]):
        v0 = sum(wk * V[:, k] for k, wk in enumerate(weights))
        v0 = v0 + 1e-3 * (rng.standard_normal(n) + 1j * rng.standard_normal(n))
        accepted: list[tuple[np.ndarray, np.ndarray]] = []
        se.arnoldi(
            apply,
            v0,
            lambda theta, vecs, got=accepted: got.append((theta, vecs)) is not None,
            steps=(2, 3, 4, 6, 10),
            tol=1e-10,
        )
        assert accepted
        for theta, vecs in accepted:
            for t, v in zip(theta, vecs.T, strict=True):
                true = np.linalg.norm(apply(v) - t * v) / np.linalg.norm(v)
                assert true <= 1e-6 * abs(t), (1 / t + sigma, true, abs(t))
