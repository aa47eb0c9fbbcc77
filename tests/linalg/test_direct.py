"""Sparse direct backends, the factor store and the memory guard."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import rheolin as rl
from rheolin.budget import MemoryBudgetError
from rheolin.linalg.direct import analyze, available_backends, resolve_backend
from rheolin.linalg.direct.superlu import SPLU_OPTIONS
from rheolin.linalg.pencil import Pencil
from rheolin.linalg.store import FactorStore, analysis_for

sys.path.insert(0, str(Path(__file__).parents[1] / "core"))
from cases import CASES

SPARSE = available_backends()


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


@pytest.mark.parametrize("backend", SPARSE)
def test_one_factorization_matches_scipy_dense(backend: str) -> None:
    rng = np.random.default_rng(1)
    A = sp.random_array((40, 40), density=0.1, rng=rng) + sp.eye_array(40) * 4
    A = sp.csc_array(A + 1j * sp.eye_array(40))
    A.sort_indices()
    B = rng.standard_normal((40, 3)) + 1j * rng.standard_normal((40, 3))
    f = analyze(backend, A.indptr, A.indices, True, sample=A.data).factor(A.data)
    ref = np.linalg.solve(A.toarray(), B)
    assert _rel(f.solve(B), ref) < 1e-12
    assert _rel(f.solve(B[:, 0]), ref[:, 0]) < 1e-12
    assert f.nbytes > 0


@pytest.mark.parametrize("case", [c for c in CASES if "sparse" in c.name], ids=lambda c: c.name)
def test_every_sparse_backend_gives_the_same_answer(case) -> None:  # type: ignore[no-untyped-def]
    """The solver catalogue's sparse cases: each backend against the independent reference
    and against each other to 1e-10."""
    method = "lti" if case.time_invariant else "gmres"
    answers = {}
    for name in SPARSE:
        sol = rl.solve(
            case.system(),
            case.harmonics,
            method=method,
            backend="lu",
            sparse_backend=name,
            rtol=1e-12,
            stability=False,
        )
        assert sol.info["sparse_backend"] == name
        if method in case.converge:
            assert sol.success, sol.message
            assert _rel(sol.q, case.reference(sol.harmonics)) < case.ref_tol
        answers[name] = sol.q
    first = answers[SPARSE[0]]
    for q in answers.values():
        assert _rel(q, first) < 1e-10


def _chain(n: int = 300) -> rl.PeriodicSystem:
    """A damped spring-mass chain with a time-varying spring in the middle."""
    main = np.full(n, 2e6)
    K0 = sp.diags_array([main, -1e6 * np.ones(n - 1), -1e6 * np.ones(n - 1)], offsets=[0, 1, -1])
    K0 = sp.csr_array(K0)
    M0 = sp.csr_array(sp.eye_array(n))
    D0 = sp.csr_array(K0 * 1e-5)
    k = n // 2
    K1 = sp.csr_array(
        ([2e5 + 0j, -2e5, -2e5, 2e5], ([k, k, k + 1, k + 1], [k, k + 1, k, k + 1])), shape=(n, n)
    )
    f = np.zeros(n, complex)
    f[3] = 1.0
    return rl.PeriodicSystem(
        50.0, M={0: M0}, D={0: D0}, K={0: K0, 1: K1, -1: K1.conj()}, f={1: f, -1: f.conj()}
    )


def test_factors_beyond_the_budget_are_refactorized_with_the_same_answer() -> None:
    system = _chain()
    H = rl.HarmonicSet.closure(system, order=6)
    full = rl.solve(system, H, method="gmres", backend="lu", stability=False, rtol=1e-12)
    ref = rl.solve(system, H, method="direct", stability=False)  # assembled coupled matrix
    assert _rel(full.q, ref.q) < 1e-10
    pencil = Pencil(system.K[0], system.D[0], system.M[0], system.omega)
    per = FactorStore(pencil, H.nonnegative).factor_bytes
    vectors = 8 * H.nonnegative.size * system.n * 16
    krylov = 201 * 2 * H.nonnegative.size * 2 * 8 + H.nonnegative.size * 4 * 16
    budget = vectors + krylov + int(4.5 * per)  # n = 0, two held, one on demand
    tight = rl.solve(
        system, H, method="gmres", backend="lu", stability=False, rtol=1e-12, memory_budget=budget
    )
    assert tight.success, tight.message
    assert "refactorized on demand" in tight.info["backend_note"]
    assert tight.info["refactorizations"] > 0
    assert _rel(tight.q, ref.q) < 1e-10


def test_superlu_store_factor_falls_back_to_partial_pivoting_when_inaccurate() -> None:
    # diagonal 0.1 passes the 0.1 pivot threshold, and its multipliers of 10 grow the last
    # column by about 11^n: the diagonal-preferring factor fails the probe, partial pivoting not
    n = 20
    A = np.diag(np.full(n, 0.1)) - np.diag(np.ones(n - 1), -1)
    A[:, -1] = 1.0
    A[-1, -1] = 0.1
    b = np.random.default_rng(3).standard_normal(n)
    ref = np.linalg.solve(A, b)
    first = spla.splu(sp.csc_array(A), **SPLU_OPTIONS).solve(b)
    assert _rel(first, ref) > 1e-8  # the case the fallback is for
    store = FactorStore(Pencil(sp.csc_array(A), None, None, 1.0), np.array([0]), "superlu")
    out: list[np.ndarray] = []
    store.use(0, lambda f: out.append(f.solve(b)))
    assert _rel(out[0], ref) < 1e-13


def test_an_oversized_problem_is_refused_before_allocation() -> None:
    n = 200_000  # 1.6 TB of vectors over 5,000 harmonics: refused from the sizes alone
    K = sp.csr_array(sp.eye_array(n))
    f = np.zeros(n)
    f[0] = 1.0
    system = rl.PeriodicSystem(1.0, M={0: K}, K={0: 2 * K}, f={1: f + 0j, -1: f + 0j})
    with pytest.raises(MemoryBudgetError, match=r"needs an estimated .* GB .* harmonics"):
        rl.solve(
            system, np.arange(-5000, 5001), method="lti", stability=False, memory_budget="20 GB"
        )


def test_analysis_is_shared_by_speeds_with_one_pattern() -> None:
    a, b = _chain(), _chain()
    p1 = Pencil(a.K[0], a.D[0], a.M[0], 10.0)
    p2 = Pencil(b.K[0], b.D[0], b.M[0], 20.0)
    name = resolve_backend("auto")
    assert analysis_for(p1, name, True, 3) is analysis_for(p2, name, True, 3)


def test_unknown_or_missing_backend_is_named() -> None:
    with pytest.raises(ValueError, match="sparse_backend"):
        resolve_backend("mumps")


def _undamped_at_2w1() -> rl.PeriodicSystem:
    """A sparse 2-DOF system undamped at 2 rad/s on w1 = 1 rad/s."""
    K1 = sp.csr_array(0.1 * np.array([[1.0, 0.5], [0.5, 1.0]]))
    f = np.array([1.0, 0.0])
    return rl.PeriodicSystem(
        1.0,
        M={0: sp.csr_array(np.eye(2))},
        K={0: sp.csr_array(np.diag([4.0, 9.0])), 1: K1, -1: K1},
        f={1: f, -1: f},
    )


@pytest.mark.skipif("pardiso" not in available_backends(), reason="needs MKL PARDISO")
def test_gmres_reports_its_recomputed_residual() -> None:
    """Under PARDISO the singular A0(2) is factorized with perturbed pivots and GMRES
    stalls; its message gives the residual of its answer, not the Krylov estimate (which
    read 0)."""
    system = _undamped_at_2w1()
    H = rl.HarmonicSet.closure(system, order=4)
    sol = rl.solve(
        system, H, method="gmres", backend="lu", sparse_backend="pardiso", stability=False
    )
    assert not sol.success
    rel = sol.info["relative_residual"]
    assert rel > 0 and f"relative residual {rel:.3g}" in sol.message


@pytest.mark.parametrize("name", [b for b in ("superlu", "umfpack") if b in available_backends()])
def test_a_singular_harmonic_is_named_once(name: str) -> None:
    """The system undamped at 2 w1: GMRES cannot run, and the message names the harmonic
    and the backend's reason once (it read "A0(n=2) is singular (n=-1) is singular (...)")."""
    system = _undamped_at_2w1()
    H = rl.HarmonicSet.closure(system, order=4)
    sol = rl.solve(system, H, method="gmres", backend="lu", sparse_backend=name, stability=False)
    assert not sol.success
    assert sol.message.startswith("A0(n=2) is singular (")
    assert "is singular (n=" not in sol.message and "n=-1" not in sol.message
