"""``method="direct"`` (and the ``auto`` fallback to it) estimates its memory before it
assembles or factorizes the coupled matrix, and refuses over the budget with the estimate:
SuperLU allocates as it fills, and a 50,000-DOF gearbox on 330 harmonics went past 19 GB
under a budget of 16 GB."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as spla

import rheolin as rl
from rheolin.data import example_path
from rheolin.harmonics.balance import HarmonicBalance
from rheolin.io import load_model
from rheolin.linalg.direct import available_backends
from rheolin.results.compute import harmonic_set
from rheolin.solvers.direct import ENTRY_BYTES, factor_estimate


@pytest.fixture(scope="module")
def gearbox() -> tuple[rl.PeriodicSystem, rl.HarmonicSet]:
    """The embedded gearbox at 3000 rpm on its order-2 set cut at 20 (30,114 unknowns)."""
    a = load_model(example_path("gearbox")).assemble(3000 * np.pi / 30)
    with pytest.warns(rl.TruncationWarning):
        return a.system, harmonic_set(a, 2, 20)


def test_coupled_entries_are_counted_before_assembly(gearbox) -> None:
    system, H = gearbox
    op = HarmonicBalance(system, H)
    assert op.coupled_entries() == op.coupled_matrix().nnz


@pytest.mark.skipif("pardiso" not in available_backends(), reason="needs MKL PARDISO")
def test_factor_estimate_covers_superlus_factor(gearbox) -> None:
    """The estimate from PARDISO's symbolic analysis is at least what SuperLU's factor and
    the matrix take when factorized, and within 3 times of it."""
    system, H = gearbox
    A = HarmonicBalance(system, H).coupled_matrix()
    estimate = factor_estimate(A)
    lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A")
    actual = ENTRY_BYTES * (lu.L.nnz + lu.U.nnz + A.nnz)
    assert estimate is not None and actual <= estimate <= 3 * actual


@pytest.mark.skipif("pardiso" not in available_backends(), reason="needs MKL PARDISO")
def test_direct_over_the_budget_is_refused_before_factorizing(gearbox) -> None:
    """60 MB: refused with the estimate; the default budget: solved, the same response as
    GMRES."""
    system, H = gearbox
    tight = rl.solve(system, H, method="direct", stability=False, memory_budget="60 MB")
    assert not tight.success
    assert "needs an estimated" in tight.message and "memory budget of 60 MB" in tight.message
    assert not np.any(tight.q)
    sol = rl.solve(system, H, method="direct", stability=False)
    ref = rl.solve(system, H, method="gmres", stability=False, rtol=1e-12)
    assert sol.success and ref.success
    assert np.linalg.norm(sol.q - ref.q) <= 1e-8 * np.linalg.norm(ref.q)
