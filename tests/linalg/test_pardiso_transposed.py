"""PARDISO's transposed and adjoint solves (used by the lattice Floquet polish for left
eigenvectors) against the matrix itself, and a lattice factor made in a later BLAS-thread
context than an earlier one (MKL crashes when an analysis outlives a thread-count change)."""

import numpy as np
import pytest
import scipy.sparse as sp
from threadpoolctl import threadpool_limits

from rheolin.linalg.direct import available_backends

pytestmark = pytest.mark.skipif(
    "pardiso" not in available_backends(), reason="MKL PARDISO not installed"
)


def _matrix(n: int, seed: int) -> sp.csc_array:
    rng = np.random.default_rng(seed)
    A = sp.random(n, n, density=4 / n, random_state=seed, data_rvs=rng.standard_normal)
    A = A + 1j * sp.random(n, n, density=4 / n, random_state=seed + 1)
    A = sp.csc_array(A + 5 * sp.eye(n))
    A.sort_indices()
    return A


@pytest.mark.parametrize("trans", ["N", "T", "H"])
def test_transposed_solves_solve_the_transposed_system(trans):
    from rheolin.linalg.direct import analyze

    A = _matrix(400, 3)
    f = analyze("pardiso", A.indptr, A.indices, True).factor(A.data)
    b = np.exp(1j * np.arange(400.0)) * np.linspace(1, 2, 400)
    op = {"N": A, "T": A.T, "H": A.conj().T}[trans]
    x = f.solve(b, trans)
    assert np.linalg.norm(op @ x - b) <= 1e-12 * np.linalg.norm(b)
    # and with SciPy's solver as the independent reference
    ref = sp.linalg.spsolve(sp.csc_array(op), b)
    assert np.allclose(x, ref, rtol=1e-11, atol=0)


def test_lattice_factor_in_a_new_thread_context():
    import rheolin as rl
    from rheolin.floquet.shift_invert import pardiso_factor
    from rheolin.harmonics import LatticeHill

    # a 2-D grid operator (little fill) above the lattice's PARDISO threshold of 8,000
    m = 95
    T = sp.diags_array([-1.0, 4.0 + 0.5j, -1.3], offsets=[-1, 0, 1], shape=(m, m))
    A = sp.csc_array(sp.kronsum(T, T))
    A.sort_indices()
    b = np.ones(A.shape[0], dtype=complex)
    one = rl.PeriodicSystem(1.0, M={0: np.eye(1)}, K={0: np.eye(1)})
    for _ in range(2):  # a new lattice (its analysis) per context, as one Floquet call each
        holder = LatticeHill(one, np.array([0]))
        with threadpool_limits(1):
            f = pardiso_factor(holder, A)
            assert f is not None
            x = f.solve(b)
        assert np.linalg.norm(A @ x - b) <= 1e-12 * np.linalg.norm(b)
