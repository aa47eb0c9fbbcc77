"""The steady-state solve of long banded chains (finely meshed shafts): the ``rows`` gmres
strategy, factors held within the memory budget by their measured size, and the checks of a
SuperLU factor (backward error, singular blocks)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import rheolin as rl
from rheolin.linalg.direct import superlu
from rheolin.linalg.direct.superlu import SuperLUBackend, splu_checked
from rheolin.linalg.errors import SingularBlockError
from rheolin.linalg.pencil import Pencil
from rheolin.linalg.store import FactorStore


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def _stiffness(n: int) -> sp.csr_array:
    main = 2e6 + 1e5 * np.linspace(0.0, 1.0, n)
    off = -1e6 * np.ones(n - 1)
    return sp.csr_array(sp.diags_array([off, main, off], offsets=[-1, 0, 1]))


def test_rows_strategy_matches_the_assembled_coupled_system(monkeypatch) -> None:
    """Time-varying stiffness on 100 of 300 DOFs (past the ``support`` strategy's 64, within
    half of the DOFs): GMRES over those rows against the sparse LU of the coupled matrix."""
    from rheolin.solvers import krylov

    monkeypatch.setattr(krylov, "PROBE_ITERATIONS", 10**6)  # not switched to ``band``
    n = 300
    main = 2.0 + np.linspace(0.0, 1.0, n)
    K0 = sp.csr_array(sp.diags_array([-np.ones(n - 1), main, -np.ones(n - 1)], offsets=[-1, 0, 1]))
    local = np.zeros(n, dtype=complex)
    local[100:200] = 0.1 * main[100:200]
    K1 = sp.csr_array(sp.diags_array(local))
    M0, D0 = sp.csr_array(sp.eye_array(n)), sp.csr_array(0.03 * sp.eye_array(n))
    f = np.zeros(n, dtype=complex)
    f[5::10] = np.exp(0.3j * np.arange(30))  # loads all along: no response decays to underflow
    system = rl.PeriodicSystem(0.9, M={0: M0}, D={0: D0}, K={0: K0, 1: K1, -1: K1}, f={1: f})
    H = rl.HarmonicSet.full(4)
    ref = rl.solve(system, H, method="direct", stability=False)
    sol = rl.solve(system, H, method="gmres", backend="lu", stability=False, rtol=1e-12)
    assert ref.success and sol.success, sol.message
    assert sol.info["strategy"] == "rows"
    assert _rel(sol.q, ref.q) < 1e-10


def _chain_system(variation: float) -> rl.PeriodicSystem:
    """300 DOFs, stiffness varying by ``variation`` of itself at 1x on every DOF (the
    ``full`` strategy: its basis is the whole half vector)."""
    n = 300
    main = 2.0 + np.linspace(0.0, 1.0, n)
    K0 = sp.csr_array(sp.diags_array([-np.ones(n - 1), main, -np.ones(n - 1)], offsets=[-1, 0, 1]))
    K1 = sp.csr_array(sp.diags_array(variation * main.astype(complex)))
    M0, D0 = sp.csr_array(sp.eye_array(n)), sp.csr_array(0.02 * sp.eye_array(n))
    f = np.zeros(n, dtype=complex)
    f[5::10] = np.exp(0.3j * np.arange(30))
    return rl.PeriodicSystem(0.9, M={0: M0}, D={0: D0}, K={0: K0, 1: K1, -1: K1}, f={1: f})


def test_a_budget_too_small_for_the_full_gmres_basis_shortens_its_restart(monkeypatch) -> None:
    """The basis of 61 vectors does not fit the budget; one of 21 (and the factors) does: the
    solve runs with the longest restart that fits, says so, and matches the sparse LU of the
    coupled matrix. A budget short of even that restart is refused before the solve."""
    from rheolin.budget import MemoryBudgetError
    from rheolin.linalg.memory import MIN_RESTART, SolveMemory
    from rheolin.solvers import krylov

    monkeypatch.setattr(krylov, "PROBE_ITERATIONS", 10**6)  # not switched to ``band``
    system, H = _chain_system(0.04), rl.HarmonicSet.full(8)
    half = 9
    shortest = SolveMemory(system.n, half, system.n, restart=MIN_RESTART).total
    free = rl.solve(system, H, method="gmres", backend="lu", stability=False, rtol=1e-12)
    assert free.info["restart"] == 60
    vector = 2 * half * system.n * 8  # one real Krylov vector of the half set
    budget = free.info["memory_estimate"] - 35 * vector  # the basis of 61 less 35 vectors
    ref = rl.solve(system, H, method="direct", stability=False)
    sol = rl.solve(
        system, H, method="gmres", backend="lu", stability=False, rtol=1e-12, memory_budget=budget
    )
    assert ref.success and sol.success, sol.message
    assert sol.info["strategy"] == "full"
    # 25 if it held the same factors; fewer held give some room back to the basis
    assert 25 <= sol.info["restart"] <= 30
    assert sol.iterations > sol.info["restart"]  # it did restart
    assert f"GMRES restarted every {sol.info['restart']} iterations (not 60)" in sol.message
    assert _rel(sol.q, ref.q) < 1e-10
    with pytest.raises(MemoryBudgetError, match=r"Krylov .* with restart 20"):
        rl.solve(system, H, method="gmres", stability=False, memory_budget=shortest - 1)


def _pencil(n: int = 400) -> Pencil:
    K0 = _stiffness(n)
    return Pencil(K0, K0 * 1e-5, sp.csr_array(sp.eye_array(n)), 300.0)


def _check_solves(store: FactorStore, pencil: Pencil, ns: np.ndarray) -> None:
    """Every factor the store gives solves its block (against dense LAPACK)."""
    b = np.random.default_rng(0).standard_normal(pencil.n)
    out: list[np.ndarray] = []
    for i in range(ns.size):
        store.use(i, lambda f: out.append(f.solve(b)))
        ref = np.linalg.solve(pencil.matrix(int(ns[i])).toarray(), b)
        assert _rel(out[-1], ref) < 1e-12


def test_factors_are_held_by_their_measured_size_within_the_budget() -> None:
    """SuperLU's size guess before factorizing would not let every factor of a chain be held
    in this budget; their measured size does, and every one is held (no refactorization)."""
    pencil, ns = _pencil(), np.arange(12)
    free = FactorStore(pencil, ns, "superlu")
    free.each(range(ns.size), lambda i, f: None)
    measured = free.held_bytes()
    budget = 3 * measured
    guess = SuperLUBackend(pencil.indptr, pencil.indices, True).factor_bytes
    assert guess * (ns.size - 1) > budget  # the case: the guess alone says "on demand"
    store = FactorStore(pencil, ns, "superlu", budget=budget)
    assert not store.on_demand
    _check_solves(store, pencil, ns)
    assert store.refactorizations == 0 and store.held_bytes() <= budget


def test_held_factors_stay_within_a_tight_budget() -> None:
    """Room for about half of the factors: the held ones stay within the budget and the
    others are refactorized on demand, every one solving its block."""
    pencil, ns = _pencil(), np.arange(12)
    free = FactorStore(pencil, ns, "superlu")
    free.each(range(ns.size), lambda i, f: None)
    budget = free.held_bytes() // 2
    store = FactorStore(pencil, ns, "superlu", budget=budget)
    assert store.on_demand
    _check_solves(store, pencil, ns)
    assert store.held_bytes() <= budget and store.refactorizations > 0


def test_stiff_block_is_factorized_once(monkeypatch) -> None:
    """A stiff tie (1e13 N/m in a chain of 1e6 N/m springs) leaves a relative residual far
    above round-off however exact the factor; its backward error is round-off, so the first
    (diagonal-preferring) factorization is kept."""
    n = 200
    K = _stiffness(n).tolil()
    K[100, 100] += 1e13
    K[101, 101] += 1e13
    K[100, 101] -= 1e13
    K[101, 100] -= 1e13
    A = sp.csc_array(K.tocsc() - 1e4 * sp.eye_array(n) + 10j * sp.eye_array(n))
    calls: list[int] = []
    real_splu = spla.splu

    def counted(*args, **kwargs):  # type: ignore[no-untyped-def]
        calls.append(1)
        return real_splu(*args, **kwargs)

    monkeypatch.setattr(superlu.spla, "splu", counted)
    lu = splu_checked(A)
    b = superlu.probe_vector(n)
    x = lu.solve(b.astype(complex))
    assert np.linalg.norm(A @ x - b) / np.linalg.norm(b) > 1e-11  # the old check failed it
    assert _rel(x, np.linalg.solve(A.toarray(), b)) < 1e-6
    assert len(calls) == 1


def test_undamped_resonance_block_is_singular() -> None:
    """``K - w^2 M`` at an eigenvalue of the chain (complex, as every harmonic ``n != 0``):
    singular to round-off; with a little damping it factorizes."""
    n = 200
    K = _stiffness(n)
    lam = np.linalg.eigvalsh(K.toarray())[7]
    A = sp.csc_array(K - lam * sp.eye_array(n), dtype=complex)
    with pytest.raises(SingularBlockError):
        splu_checked(A, 3)
    damped = sp.csc_array(A + 1j * 1e3 * sp.eye_array(n))
    b = superlu.probe_vector(n)
    x = splu_checked(damped).solve(b.astype(complex))
    assert _rel(x, np.linalg.solve(damped.toarray(), b)) < 1e-10


def _simply_supported_beam(elements: int, length: float, ei: float, rho_a: float) -> tuple:
    """Euler-Bernoulli beam of Hermite elements (deflection and slope per node), pinned at
    both ends: stiffness, mass and the consistent load of a uniform 1 N/m."""
    h = length / elements
    k = (ei / h**3) * np.array(
        [[12, 6 * h, -12, 6 * h], [6 * h, 4 * h * h, -6 * h, 2 * h * h],
         [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h * h, -6 * h, 4 * h * h]]
    )  # fmt: skip
    m = (rho_a * h / 420) * np.array(
        [[156, 22 * h, 54, -13 * h], [22 * h, 4 * h * h, 13 * h, -3 * h * h],
         [54, 13 * h, 156, -22 * h], [-13 * h, -3 * h * h, -22 * h, 4 * h * h]]
    )  # fmt: skip
    f = np.array([h / 2, h * h / 12, h / 2, -h * h / 12])
    n = 2 * (elements + 1)
    idx = 2 * np.arange(elements)[:, None] + np.arange(4)
    rows, cols = np.repeat(idx, 4, axis=1).ravel(), np.tile(idx, 4).ravel()
    K = sp.csc_array((np.tile(k.ravel(), elements), (rows, cols)), shape=(n, n))
    M = sp.csc_array((np.tile(m.ravel(), elements), (rows, cols)), shape=(n, n))
    load = np.bincount(idx.ravel(), np.tile(f, elements), minlength=n)
    keep = np.setdiff1d(np.arange(n), [0, n - 2])  # no deflection at the supports
    return K[keep][:, keep], M[keep][:, keep], load[keep], keep


def test_finely_meshed_beam_block_is_not_singular() -> None:
    """A steel shaft (1 m, 50 mm) meshed into 2,000 beam elements has an amplification
    ``||A||_F ||A^-1 b|| / ||b||`` above ``1 / PIVOT_RTOL`` at every harmonic (translations
    against rotations of 0.5 mm elements, and the fourth-order bending operator): it once
    made the steady state of the gearbox with its shafts at 50,000 DOF fail as "A0(437) is
    singular", far from any resonance. The check now measures the symmetrically scaled
    matrix: the block factorizes, and its static deflection under a uniform load is the
    closed form ``q x (L^3 - 2 L x^2 + x^3) / (24 EI)`` (exact at the nodes of Hermite
    elements). To 1e-3: at 0.5 mm elements double precision keeps about 1e-4 of the
    deflection (LAPACK's dense solve of the same block is 1.25e-4 off too; the error grows
    tenfold with every doubling of the mesh)."""
    length, ei, rho_a = 1.0, 210e9 * np.pi * 0.05**4 / 64, 7850 * np.pi * 0.05**2 / 4
    K, M, load, keep = _simply_supported_beam(2000, length, ei, rho_a)
    A = sp.csc_array(K + 1e-3j * M)  # complex, as every harmonic n != 0; far below mode 1
    b = superlu.probe_vector(A.shape[0])
    x = spla.splu(A).solve(b.astype(complex))
    unscaled = np.linalg.norm(A.data) * np.linalg.norm(x) / np.linalg.norm(b)
    assert unscaled * superlu.PIVOT_RTOL > 1.0  # the unscaled check refused this block
    q = splu_checked(A, 437).solve(load.astype(complex))
    nodes = keep[keep % 2 == 0] // 2
    x_n = nodes * (length / 2000)
    exact = x_n * (length**3 - 2 * length * x_n**2 + x_n**3) / (24 * ei)
    assert _rel(q[keep % 2 == 0].real, exact) < 1e-3
