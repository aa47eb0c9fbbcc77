"""Floquet decisions on badly scaled systems, truncation convergence, and the sparse path.

* Stiff springs (1e12 N/m) next to soft ones (1e4 N/m), time-invariant: exponents against
  ``scipy.linalg.eig`` of the first-order matrix; damped -> stable, undamped -> marginal.
* A Mathieu oscillator hung on a 1e12 N/m support: stability on both sides of the transition
  curves from ``scipy.special``.
* Sparse shift-invert against dense QZ on a mid-size asymmetric rotor.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
from scipy.special import mathieu_a, mathieu_b

import rheolin as rl


def _chain(damping: float) -> rl.PeriodicSystem:
    k = np.array([1e12, 1e4, 1e12, 3e4, 1e12])  # springs: ground-1, 1-2, ..., 4-5
    n = k.size
    K = np.diag(k + np.append(k[1:], 0.0)) - np.diag(k[1:], 1) - np.diag(k[1:], -1)
    M = np.diag([0.3, 2.0, 0.1, 1.5, 0.05])
    D = damping * K / 1e4 + damping * np.eye(n)
    return rl.PeriodicSystem(50.0, M={0: M}, D={0: D}, K={0: K})


@pytest.mark.parametrize("damping", [0.0, 0.05])
def test_stiff_springs_against_scipy_eig(damping: float) -> None:
    s = _chain(damping)
    M, D, K = s.M[0], s.D.get(0, np.zeros_like(s.M[0])), s.K[0]
    n = s.n
    Mi = np.linalg.inv(M)
    first_order = np.block([[np.zeros((n, n)), np.eye(n)], [-Mi @ K, -Mi @ D]])
    ref = sla.eig(first_order, right=False)
    for N in (0, 3):
        res = rl.floquet(s, N)
        assert res.stable, (N, res.max_real, res.tol)
        assert res.marginal == (damping == 0.0)
        assert res.converged
        # same spectrum, folded into (-w/2, w/2]
        folded = ref - 1j * s.omega * np.ceil(ref.imag / s.omega - 0.5)
        for lam in folded:
            assert np.min(np.abs(res.exponents - lam)) < 1e-9 * max(abs(ref).max(), 1.0)
        np.testing.assert_allclose(
            np.sort(res.exponents.real), np.sort(ref.real), rtol=1e-6, atol=res.tol
        )


@pytest.mark.parametrize(("m", "q"), [(1, 1.0), (2, 1.0), (1, 0.5)])
def test_mathieu_on_stiff_support(m: int, q: float) -> None:
    """x1 on a 1e12 support, x2 = y on the Mathieu spring ``a - 2 q cos 2t`` to x1."""
    d = 0.02 * (mathieu_a(m, q) - mathieu_b(m, q))
    for a, unstable in (
        (mathieu_b(m, q) + d, True),  # inside (b_m, a_m)
        (mathieu_a(m, q) - d, True),
        (mathieu_b(m, q) - d, False),
        (mathieu_a(m, q) + d, False),
    ):
        Kspring = np.array([[1.0, -1.0], [-1.0, 1.0]])
        K0 = a * Kspring + np.diag([1e12, 0.0])
        s = rl.PeriodicSystem(
            2.0, M={0: np.diag([1e-2, 1.0])}, K={0: K0, 1: -q * Kspring.astype(complex)}
        )
        res = rl.floquet(s, 12)
        assert res.stable == (not unstable), (m, q, a, res.max_real, res.tol)
        if not unstable:
            assert res.marginal


def test_sparse_agrees_with_dense_on_asymmetric_rotor() -> None:
    """A 16-DOF chain of asymmetric rotors (K harmonics 0, +-2) inside an instability band."""
    n_r, W = 8, 1.0
    rng = np.random.default_rng(0)
    km = 1.0 + 0.5 * rng.random(n_r)
    kd = 0.15 * km
    K0 = np.zeros((2 * n_r, 2 * n_r), complex)
    K2 = np.zeros_like(K0)
    for i in range(n_r):
        sl = slice(2 * i, 2 * i + 2)
        K0[sl, sl] += km[i] * np.eye(2)
        K2[sl, sl] += kd[i] / 2 * np.array([[1, -1j], [-1j, -1]])
        if i + 1 < n_r:
            c = 0.05 * np.eye(2)
            sj = slice(2 * i + 2, 2 * i + 4)
            K0[sl, sl] += c
            K0[sj, sj] += c
            K0[sl, sj] -= c
            K0[sj, sl] -= c
    s = rl.PeriodicSystem(
        W, M={0: np.eye(2 * n_r)}, D={0: 0.01 * np.eye(2 * n_r)}, K={0: K0.real, 2: K2}
    )
    dense = rl.floquet(s, 6, method="dense")
    sparse = rl.floquet(s, 6, method="sparse", frequencies=(0.0, 3.0))
    assert not dense.stable and not sparse.stable
    assert sparse.max_real == pytest.approx(dense.max_real, rel=1e-9)
    # every dense exponent within the searched band is found by the sparse path
    near = dense.exponents[np.abs(dense.exponents.real) < sparse.band]
    for lam in near:
        assert np.min(np.abs(sparse.exponents - lam)) < 1e-8 * max(abs(lam), 1.0)
    assert sparse.info["factorizations"] >= 1


def _monodromy_stable(a: float, q: float, z: float) -> bool:
    """Damped Mathieu ``y'' + 2 z y' + (a - 2 q cos 2t) y = 0``: stable iff both multipliers of
    the monodromy matrix over one period ``pi`` (``solve_ivp``, tight tolerances) are < 1."""
    from scipy.integrate import solve_ivp

    def rhs(t, y):
        return [y[1], -2 * z * y[1] - (a - 2 * q * np.cos(2 * t)) * y[0]]

    with np.errstate(under="ignore"):
        cols = [
            solve_ivp(rhs, (0, np.pi), y0, rtol=1e-12, atol=1e-14, method="DOP853").y[:, -1]
            for y0 in ([1.0, 0.0], [0.0, 1.0])
        ]
    return bool(np.max(np.abs(np.linalg.eigvals(np.column_stack(cols)))) < 1.0)


def test_a_decided_verdict_matches_the_monodromy_matrix() -> None:
    """Damped Mathieu over a grid crossing the first bands, Hill truncations of 1..4
    harmonics: whenever ``decided`` is True the verdict equals the one of the monodromy
    matrix; coarse truncations near the bands are flagged undecided instead."""
    undecided = 0
    for a in np.linspace(-0.5, 6.0, 11):
        for q in (0.5, 1.5, 3.0):
            for z in (0.02, 0.2, 2.0):
                s = rl.PeriodicSystem(
                    2.0,
                    M={0: np.eye(1)},
                    D={0: 2 * z * np.eye(1)},
                    K={0: a * np.eye(1), 1: -q * np.eye(1)},
                )
                truth = _monodromy_stable(a, q, z)
                for N in (1, 2, 3, 4):
                    res = rl.floquet(s, N)
                    if res.decided:
                        assert res.stable == truth, (a, q, z, N, res.exponents)
                    else:
                        undecided += 1
                assert rl.floquet(s, 10).decided
    assert 0 < undecided < 400


def test_verdict_is_undecided_only_when_the_truncation_could_flip_it() -> None:
    """Damped Mathieu inside the first band (unstable by its monodromy matrix): two harmonics
    call it stable, and the verdict is flagged undecided. The example rotor at its stability
    truncation: heavily damped high modes (Re ~ -1700 1/s) are not converged, yet the
    verdict is decided and equals that of a converged truncation."""
    q, z = 0.3, 0.05
    a = 0.5 * (mathieu_a(1, q) + mathieu_b(1, q))
    assert not _monodromy_stable(a, q, z)
    s = rl.PeriodicSystem(
        2.0, M={0: np.eye(1)}, D={0: 2 * z * np.eye(1)}, K={0: a * np.eye(1), 1: -q * np.eye(1)}
    )
    coarse = rl.floquet(s, 2)
    assert coarse.stable and not coarse.converged and not coarse.decided
    assert not rl.floquet(s, 10).stable

    from rheolin.data import example_path
    from rheolin.io import load_model
    from rheolin.solvers.solve import stability_harmonics

    system = load_model(example_path("rotor")).assemble(3000 * np.pi / 30).system
    res = rl.floquet(system, stability_harmonics(system))
    assert not res.converged and res.decided and res.stable
    assert res.exponents[res.edge_weight > 1e-6].real.max() < -1000
    ref = rl.floquet(system, 12)
    assert ref.converged and ref.stable
