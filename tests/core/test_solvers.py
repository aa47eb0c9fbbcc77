"""Every method on the shared catalogue (``cases.py``), plus argument errors and ``auto``."""

from __future__ import annotations

import re

import numpy as np
import pytest
from cases import CASES, METHODS, Case, gravity_rotor

import rheolin as rl


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


#: Inverses of A0(n) (``rheolin.linalg``); ``direct`` uses none, so it runs once.
BACKENDS = ("auto", "lu", "dense", "modal")
RUNS = [(m, b) for m in METHODS for b in BACKENDS if m != "direct" or b == "auto"]


@pytest.mark.parametrize(("method", "backend"), RUNS)
@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
def test_catalogue(case: Case, method: str, backend: str) -> None:
    """Every method with every backend against the case's independent reference."""
    system = case.system()
    if method == "lti" and not case.time_invariant:
        with pytest.raises(ValueError, match="lti"):
            rl.solve(system, case.harmonics, method="lti", backend=backend)
        return
    rtol = 1e-10
    sol = rl.solve(system, case.harmonics, method=method, rtol=rtol, backend=backend)
    assert sol.method == method
    assert np.array_equal(sol.harmonics, case.harmonics.indices)
    if method in case.converge:
        assert sol.success, sol.message
        assert sol.status == 0
        assert sol.residual <= rtol, sol.residual
        assert sol.stable is True  # small systems: solve checks Floquet stability by default
        ref = case.reference(sol.harmonics)
        assert _rel(sol.q, ref) < case.ref_tol
        # a real response: q_{-n} = conj(q_n)
        np.testing.assert_allclose(sol.q[::-1], np.conj(sol.q), rtol=0, atol=1e-14 * abs(ref).max())
        if method == "gmres":
            hist = np.asarray(sol.history)
            assert sol.iterations == hist.size
            if case.time_invariant:
                assert sol.iterations <= 1  # dA = 0: the preconditioner is the inverse
            else:
                assert sol.iterations >= 1
                assert np.all(np.diff(hist) <= 1e-12 * hist[0]), hist  # minimal residual
                assert hist[-1] <= rtol
        if method == "perturbation":
            assert sol.history[-1] <= rtol
    else:
        allowed = case.fail[method]
        assert not sol.success, sol.message
        assert sol.status in allowed, (sol.status, sol.message)
        assert sol.message
        if sol.status == 4:
            # the solution exists and solves the truncated system; only its physics is wrong
            assert sol.stable is False and sol.max_floquet_real > 0
            assert _rel(sol.q, case.reference(sol.harmonics)) < case.ref_tol


def test_gravity_case_gmres_few_iterations_and_perturbation_contraction() -> None:
    """docs/solvers.md: at half the critical speed the perturbation contraction factor is
    ``rho = sqrt(eps^2 / (2 zeta)) = 1.414`` although the rotor is stable; GMRES needs < 10."""
    system = gravity_rotor().system()
    sol = rl.solve(system, 16, method="gmres")
    assert sol.success and sol.iterations < 10, sol
    pert = rl.solve(system, 16, method="perturbation", maxiter=200)
    assert not pert.success and pert.status in (1, 2)
    # Residuals grow by rho^2 = 2 every second iteration (q_0 -> q_{±2} -> q_0)
    h = np.asarray(pert.history)
    two_step = h[2:] / h[:-2]
    assert np.allclose(two_step[-4:], 2.0, rtol=0.05), two_step


def test_gravity_case_auto_uses_gmres() -> None:
    system = gravity_rotor().system()
    sol = rl.solve(system, 16)
    assert sol.success and sol.method == "gmres"


def test_auto_time_invariant_uses_lti() -> None:
    from cases import chain_reference, chain_system

    sol = rl.solve(chain_system(), 4)
    assert sol.success and sol.method == "lti"
    assert _rel(sol.q, chain_reference(sol.harmonics)) < 1e-12


def test_unstable_band_reports_floquet_growth() -> None:
    """Inside the band the rotating-frame equation has a real positive exponent: compare
    ``max_floquet_real`` with the closed-form eigenvalues of the rotating-frame system."""
    from cases import JEFFCOTT_INSIDE, Jeffcott

    rotor = Jeffcott(W=JEFFCOTT_INSIDE)
    sol = rl.solve(rotor.system(), 5, method="gmres")
    assert sol.status == 4 and sol.stable is False
    # rotating frame: m xi'' + (c I + 2 m W J) xi' + (diag(kx, ky) - m W^2 I + c W J) xi = 0,
    # J = [[0, -1], [1, 0]] (time invariant): eigenvalues by a companion matrix.
    m, c, W = rotor.m, rotor.c, rotor.W
    J = np.array([[0.0, -1.0], [1.0, 0.0]])
    Kr = np.diag([rotor.kx, rotor.ky]) - m * W**2 * np.eye(2) + c * W * J
    Dr = c * np.eye(2) + 2 * m * W * J
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Kr / m, -Dr / m]])
    growth = np.linalg.eigvals(A).real.max()
    assert growth > 0
    assert sol.max_floquet_real == pytest.approx(growth, rel=1e-8)


def test_callback_and_maxiter() -> None:
    system = gravity_rotor().system()
    seen: list[tuple[int, float]] = []
    sol = rl.solve(system, 16, method="gmres", callback=lambda i, r: seen.append((i, r)))
    assert [r for _, r in seen] == sol.history
    capped = rl.solve(system, 16, method="gmres", maxiter=2, rtol=1e-14)
    assert not capped.success and capped.status == 1 and capped.iterations <= 2


@pytest.mark.parametrize("backend", BACKENDS)
def test_singular_time_averaged_system_is_status_3(backend: str) -> None:
    """Undamped oscillator forced exactly at resonance: ``A0(1)`` is singular."""
    s = rl.PeriodicSystem(2.0, M={0: np.eye(1)}, K={0: 4.0 * np.eye(1)}, f={1: np.ones(1)})
    sol = rl.solve(s, 2, method="lti", backend=backend)
    assert not sol.success and sol.status == 3


def test_modal_backend_falls_back_to_lu_for_a_massless_dof() -> None:
    """A massless DOF hanging on a spring makes ``M_0`` singular: no modal resolvent; the LU
    answer is the closed form ``x_1 = x_2 = f / (k1 - m W^2 + i c W)``."""
    W, m, k1, k2, c = 3.0, 2.0, 50.0, 30.0, 0.4
    M = np.diag([m, 0.0])
    K = np.array([[k1 + k2, -k2], [-k2, k2]])
    D = np.diag([c, 0.0])
    s = rl.PeriodicSystem(W, M={0: M}, D={0: D}, K={0: K}, f={1: np.array([1.0, 0.0])})
    sol = rl.solve(s, 1, method="lti", backend="modal", stability=False)
    assert sol.success and "modal resolvent not used" in sol.info["backend_note"]
    x = 1.0 / (k1 - m * W**2 + 1j * c * W)  # the massless DOF follows: x_2 = x_1
    np.testing.assert_allclose(sol.harmonic(1), [x, x], rtol=1e-12)


def test_warm_start_from_the_solution_needs_no_iteration() -> None:
    """``x0`` = the converged answer: gmres stops at once, perturbation after one step, both
    on the dense harmonic-balance reference; a guess of the wrong size is refused."""
    case = next(c for c in CASES if c.name == "gravity_half_critical")
    system = case.system()
    cold = rl.solve(system, case.harmonics, method="gmres", rtol=1e-12)
    assert cold.iterations >= 3
    warm = rl.solve(system, case.harmonics, method="gmres", rtol=1e-10, x0=cold)
    assert warm.success and warm.iterations <= 1 and warm.info["warm_start"]
    assert _rel(warm.q, case.reference(warm.harmonics)) < case.ref_tol
    pert = rl.solve(system, case.harmonics, method="perturbation", rtol=1e-10, x0=cold.q)
    assert pert.success and pert.iterations <= 1
    assert _rel(pert.q, case.reference(pert.harmonics)) < case.ref_tol
    with pytest.raises(ValueError, match="x0"):
        rl.solve(system, case.harmonics, x0=cold.q[:, :1])


def test_zero_load_gives_zero_response() -> None:
    s = rl.PeriodicSystem(1.0, M={0: np.eye(2)}, K={0: np.eye(2)})
    sol = rl.solve(s, 3, method="lti")
    assert sol.success and not sol.q.any()


# --------------------------------------------------------------------------- argument errors
def _small() -> rl.PeriodicSystem:
    return rl.PeriodicSystem(
        1.0, M={0: np.eye(2)}, D={0: 0.1 * np.eye(2)}, K={0: np.eye(2)}, f={1: np.ones(2)}
    )


def test_lti_refuses_time_varying_system() -> None:
    s = rl.PeriodicSystem(
        1.0, M={0: np.eye(1)}, K={0: np.eye(1), 2: 0.1 * np.eye(1)}, f={1: np.ones(1)}
    )
    with pytest.raises(ValueError, match=re.escape("method='lti'")):
        rl.solve(s, 3, method="lti")


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"method": "newton"}, "`method`"),
        ({"method": None}, "`method`"),
        ({"rtol": 0.0}, "`rtol`"),
        ({"rtol": 1.5}, "`rtol`"),
        ({"rtol": -1e-8}, "`rtol`"),
        ({"rtol": "1e-8"}, "`rtol`"),
        ({"maxiter": 0}, "`maxiter`"),
    ],
)
def test_solve_bad_options(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        rl.solve(_small(), 3, **kwargs)


@pytest.mark.parametrize("harmonics", [[], [0.5, 1], "abc", -1, True])
def test_solve_bad_harmonics(harmonics: object) -> None:
    with pytest.raises(ValueError, match=r"harmonics|`N`"):
        rl.solve(_small(), harmonics)


def test_solve_bad_system() -> None:
    with pytest.raises(TypeError, match="`system`"):
        rl.solve({"M": 1}, 3)  # type: ignore[arg-type]


@pytest.mark.parametrize("sparse", [False, True])
def test_support_coupling_matches_the_assembled_coupled_matrix(sparse: bool) -> None:
    """``dA q`` on its support (the gmres inner product) equals the assembled matrix's product.

    Random local time variation at harmonics 1, 2 and 5 on DOFs 1-3 of a 6-DOF system: rows
    ``m >= 0`` read sources ``n = m - k < 0`` (conjugated), which the half storage must get right.
    """
    from rheolin.harmonics.balance import HarmonicBalance

    rng = np.random.default_rng(3)
    n = 6

    def local(scale: float) -> np.ndarray:
        x = np.zeros((n, n), dtype=complex)
        x[1:4, 1:4] = scale * (rng.standard_normal((3, 3)) + 1j * rng.standard_normal((3, 3)))
        return x

    M = {0: np.eye(n), 2: local(0.05)}
    D = {0: 0.02 * np.eye(n), 1: local(0.01)}
    K = {0: np.diag(np.arange(1.0, n + 1)), 1: local(0.2), 5: local(0.1)}
    if sparse:
        import scipy.sparse as sps

        M, D, K = ({k: sps.csr_array(v) for k, v in x.items()} for x in (M, D, K))
    system = rl.PeriodicSystem(0.7, M=M, D=D, K=K, f={1: np.ones(n)})
    op = HarmonicBalance(system, rl.HarmonicSet.full(7), workers=1)
    rows, cols = op.support
    assert list(rows) == [1, 2, 3] and list(cols) == [1, 2, 3]
    Q = rng.standard_normal((op.pos.size, n)) + 1j * rng.standard_normal((op.pos.size, n))
    Q[0] = Q[0].real  # the mean of a real signal
    A = op.coupled_matrix()
    A0 = [op.A0_matrix(int(m)) for m in op.full]
    full = op.expand(Q)
    Aq = (A @ full.ravel()).reshape(full.shape)
    dAq = Aq - np.array([a @ q for a, q in zip(A0, full, strict=True)])
    expected = op.half(dAq)[:, rows]
    got = op.apply_dA_support(Q[:, cols], rows, cols)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12 * np.abs(expected).max())


def test_threads_come_from_one_long_lived_pool() -> None:
    """``workers=2`` with a backend that releases the GIL (SuperLU does not: it runs serially):
    the reference answer, and the same two worker threads for every solve (a new pool per
    factorization grew the resident memory by 450 MB over 500 solves)."""
    import threading

    from rheolin.linalg.direct import available_backends

    threaded = [b for b in ("umfpack", "pardiso") if b in available_backends()]
    if not threaded:
        pytest.skip("no sparse backend that releases the GIL is installed")
    case = next(c for c in CASES if c.name == "gravity_half_critical_sparse")
    system = case.system()

    def pool_threads() -> set[int]:
        return {t.ident for t in threading.enumerate() if t.name.startswith("rheolin-2")}

    seen = []
    for _ in range(3):
        sol = rl.solve(
            system,
            case.harmonics,
            backend="lu",
            sparse_backend=threaded[0],
            workers=2,
            stability=False,
        )
        assert sol.success and _rel(sol.q, case.reference(sol.harmonics)) < case.ref_tol
        seen.append(pool_threads())
    assert seen[0] and seen[0] == seen[1] == seen[2]


@pytest.mark.parametrize("backend", ["lu", "dense", "modal"])
def test_full_strategy_on_every_backend_matches_direct(backend: str, monkeypatch) -> None:
    """Time variation on every DOF of an 80-DOF damped chain (the ``full`` gmres strategy,
    support > 64, kept from switching to ``band``): each backend against the assembled
    coupled system's sparse LU."""
    import scipy.sparse as sps

    from rheolin.solvers import krylov

    monkeypatch.setattr(krylov, "PROBE_ITERATIONS", 10**6)

    n = 80
    main = 2.0 + np.linspace(0.0, 1.0, n)
    K0 = sps.diags([-np.ones(n - 1), main, -np.ones(n - 1)], [-1, 0, 1]).tocsr()
    K2 = sps.diags(0.05 * main.astype(complex)).tocsr()
    M0, D0 = sps.identity(n, format="csr"), 0.03 * sps.identity(n, format="csr")
    f = np.zeros(n, dtype=complex)
    f[[3, 40, 77]] = [1.0, -0.5j, 0.3]
    system = rl.PeriodicSystem(0.9, M={0: M0}, D={0: D0}, K={0: K0, 2: K2}, f={1: f})
    H = rl.HarmonicSet.full(9)
    ref = rl.solve(system, H, method="direct", stability=False)
    sol = rl.solve(system, H, method="gmres", backend=backend, stability=False, rtol=1e-12)
    assert ref.success and sol.success, sol.message
    assert sol.info["strategy"] == "full" and sol.info["backend"] == backend
    assert _rel(sol.q, ref.q) < 1e-10


@pytest.mark.parametrize("sweeps", [0, 8, 10**6])
def test_support_strategy_by_solve_sweeps_then_g_matches_direct(sweeps: int, monkeypatch) -> None:
    """Local time variation on 20 DOFs of an 80-DOF damped chain (the ``support`` strategy on
    sparse LU factors): products by solve sweeps only, by ``G`` only, and both in one solve
    (sweeps for the first five products, a quarter of the 20 support DOFs, then ``G``), each
    against the assembled coupled system's sparse LU."""
    import scipy.sparse as sps

    from rheolin.solvers import krylov

    monkeypatch.setattr(krylov, "SWEEPS_BEFORE_G", sweeps)
    n = 80
    main = 2.0 + np.linspace(0.0, 1.0, n)
    K0 = sps.diags([-np.ones(n - 1), main, -np.ones(n - 1)], [-1, 0, 1]).tocsr()
    local = np.zeros(n, dtype=complex)
    local[30:50] = 0.4 * main[30:50]
    K1 = sps.diags(local).tocsr()
    M0, D0 = sps.identity(n, format="csr"), 0.03 * sps.identity(n, format="csr")
    f = np.zeros(n, dtype=complex)
    f[[3, 40, 77]] = [1.0, -0.5j, 0.3]
    system = rl.PeriodicSystem(0.9, M={0: M0}, D={0: D0}, K={0: K0, 1: K1, -1: K1}, f={1: f})
    H = rl.HarmonicSet.full(12)
    ref = rl.solve(system, H, method="direct", stability=False)
    sol = rl.solve(system, H, method="gmres", backend="lu", stability=False, rtol=1e-12)
    assert ref.success and sol.success, sol.message
    assert sol.info["strategy"] == "support" and sol.info["backend"] == "lu"
    assert sol.iterations > 5  # the mixed case switches to G within the solve
    assert _rel(sol.q, ref.q) < 1e-10
