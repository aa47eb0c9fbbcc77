"""Floquet verdicts for models above the dense limit of the time-averaged modes (issue 31).

References, each independent of the method under test:

* the example rotor's 3-node model by the dense Hill method (the verdicts and largest real
  parts the finely meshed rotor must reproduce to its discretization error);
* the dense lattice method (every time-averaged mode, section 3 of docs/stability.md) on
  models just below the old limit, against the band method forced on the same system;
* monodromy matrices (``solve_ivp``, DOP853) for the body-frame transformation and for a
  hidden high-frequency parametric instability;
* dense eigenvalues for the energy bound on the time-averaged modes left out.
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import rheolin as rl
from rheolin.budget import MemoryBudgetError
from rheolin.data.fine import mesh_chain, refined_example
from rheolin.io import parse_model

sys.path.insert(0, str(Path(__file__).parents[1] / "core"))
from cases import integrate

RPM = np.pi / 30


def _assembled(text: str, rpm: float):
    model = parse_model(text).model
    return model.speed_template().assemble(rpm * RPM)


def _monodromy_max_real(system: rl.PeriodicSystem, rtol: float = 1e-11) -> float:
    n, period = system.n, 2 * np.pi / system.omega

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        M, D, K = (np.asarray(system.evaluate(name, t)) for name in "MDK")
        q, v = y[:n], y[n:]
        return np.concatenate([v, np.linalg.solve(M, -D @ v - K @ q)])

    cols = [
        integrate(rhs, (0.0, period), e, rtol=rtol, atol=1e-14, method="DOP853").y[:, -1]
        for e in np.eye(2 * n)
    ]
    mu = np.linalg.eigvals(np.column_stack(cols))
    return float(np.log(np.abs(mu).max()) / period)


def test_fine_rotor_has_the_unstable_verdict_of_the_three_node_model() -> None:
    """335 shaft nodes (2,010 DOF, past the dense limit) at 4220 rpm, inside the
    asymmetric-shaft band: decided unstable, and the 3-node model's leading exponent (dense
    Hill) found to the discretization error, its inertial frequency included (7e-5 relative
    measured at 401 nodes). The stable speed is checked through ``rheolin run`` below. The
    verdict's memory estimate bounds what it allocates (NumPy and Python, under
    ``tracemalloc``) and is not far above it."""
    import tracemalloc

    ref = rl.floquet(_assembled(refined_example("rotor", 3), 4220.0).system, 12, method="dense")
    assert not ref.stable
    system = _assembled(refined_example("rotor", 335), 4220.0).system
    tracemalloc.start()
    try:
        res = rl.floquet(system)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak <= res.info["memory_estimate"] <= 4 * peak, (peak, res.info["memory_estimate"])
    assert res.decided and not res.stable, res.info.get("band")
    assert res.info["band"]["frames"] == ["rotor"]
    z, w = ref.exponents[0], ref.omega
    d = np.abs(res.exponents.real - z.real) / abs(z.real)
    copy = np.abs((res.exponents.imag - z.imag + w / 2) % w - w / 2)
    assert np.min(np.maximum(d, copy / max(abs(z), w))) <= 2e-3, z
    assert abs(res.max_real - ref.max_real) <= 2e-3 * abs(ref.max_real)


def test_continued_band_starts_at_the_last_speeds_size(monkeypatch) -> None:
    """Over a run-up the band of the next speed starts at the size the last certified band
    was asked for: the 335-node rotor inside its asymmetric-shaft band needs 80 modes (40 are
    not certified); continued from 4220 to 4225 rpm it builds one band of 80, and its
    verdict and largest real part are those of the 3-node model's dense Hill method there."""
    from rheolin.floquet import Continuation
    from rheolin.floquet import band as band_module

    built: list[int] = []
    original = band_module.BandAveraged

    class Counted(original):  # type: ignore[misc, valid-type]
        def __init__(self, system: rl.PeriodicSystem, modes: int = 40) -> None:
            built.append(int(modes))
            super().__init__(system, modes)

    monkeypatch.setattr(band_module, "BandAveraged", Counted)
    text = refined_example("rotor", 335)
    cont = Continuation()
    first = rl.floquet(_assembled(text, 4220.0).system, continuation=cont)
    assert built == [40, 80] and first.info["band"]["modes"] == 80
    built.clear()
    res = rl.floquet(_assembled(text, 4225.0).system, continuation=cont)
    assert built == [80] and res.info["band"]["certified"]
    ref = rl.floquet(_assembled(refined_example("rotor", 3), 4225.0).system, 12, method="dense")
    assert res.decided and not res.stable and not ref.stable
    assert abs(res.max_real - ref.max_real) <= 2e-3 * abs(ref.max_real)


@pytest.mark.parametrize("rpm", [3000.0, 4220.0])
def test_band_method_matches_the_dense_method_below_the_limit(rpm: float) -> None:
    """A 41-node rotor (246 DOF) in its shaft's frame: the band method (40 modes) and the
    dense lattice method (every mode) give the same verdict, and every exponent of the band
    is one of the dense method's within the two results' uncertainties (the dense method
    also has the high modes' exponents, outside the band)."""
    from rheolin.floquet.large import in_body_frames

    s, names = in_body_frames(_assembled(refined_example("rotor", 41), rpm).system)
    assert names == ["rotor"]
    dense = rl.floquet(s)
    band = rl.floquet(s, band=40)
    assert "band" not in dense.info and band.info["band"]["modes"] == 40
    assert dense.decided and band.decided
    assert band.stable is dense.stable
    w = s.omega
    unc_b = band.info["uncertainty"] + band.tolerances
    unc_d = dense.info["uncertainty"] + dense.tolerances
    for z, u in zip(band.exponents, unc_b, strict=True):
        gap = np.abs(dense.exponents.real - z.real) + np.abs(
            (dense.exponents.imag - z.imag + w / 2) % w - w / 2
        )
        j = int(np.argmin(gap))
        assert gap[j] <= 2 * (u + unc_d[j]) + 1e-9 * max(abs(z), w), (z, dense.exponents[j])


def test_body_frame_keeps_the_floquet_exponents() -> None:
    """A mass on a shaft stiffer in one body axis than the other, spinning about z inside
    its instability band (``sqrt(k_x/m) < W < sqrt(k_y/m)``), damped in the inertial frame,
    written in its own frame (``q = R(t) p``): the largest real part equals the monodromy
    matrix's of the inertial system, and the exponents are copies of the inertial ones
    (moved by multiples of i w1). The frames of the rotor's shaft are exercised by the
    tests above."""
    from rheolin.system.frames import BodyFrame, rotate

    kx, ky, kz, c, W = 1.0e4, 1.6e4, 3.0e4, 4.0, 112.0
    sym, dif = (kx + ky) / 2, (kx - ky) / 2
    K2 = dif / 2 * np.array([[1, -1j, 0], [-1j, -1, 0], [0, 0, 0]])  # R diag(kx, ky) R^T
    s = rl.PeriodicSystem(
        W,
        M={0: np.eye(3)},
        D={0: c * np.eye(3)},
        K={0: np.diag([sym, sym, kz]), 2: K2, -2: K2.conj()},
    )
    rotated = rotate(s, [BodyFrame("shaft", 1, (0.0, 0.0, 1.0), np.array([[0, 1, 2]]))])
    assert rotated.coefficient_harmonics == []  # time-invariant in its own frame
    truth = _monodromy_max_real(s)
    assert truth > 0
    ref = rl.floquet(s, 12, method="dense")
    got = rl.floquet(rotated, 12, method="dense")
    assert abs(got.max_real - truth) <= 1e-6 * abs(truth)
    for z in got.exponents:
        d = np.abs(ref.exponents.real - z.real) + np.abs(
            (ref.exponents.imag - z.imag + W / 2) % W - W / 2
        )
        assert d.min() <= 1e-6 * max(abs(z), W)


def test_energy_bound_on_the_modes_left_out() -> None:
    """Random damped gyroscopic systems with circulatory terms and softening: every
    time-averaged eigenvalue with ``|lambda| > max(sqrt(gamma), rho)`` has ``Re <= 0``
    (dense eigenvalues), with ``gamma`` and ``rho`` from
    :func:`rheolin.floquet.complement.energy_radius`."""
    from rheolin.floquet.complement import energy_radius

    rng = np.random.default_rng(7)
    for _ in range(20):
        n = 12
        A = rng.standard_normal((n, n))
        M = A @ A.T + n * np.eye(n)
        B = rng.standard_normal((n, n))
        K = B @ B.T - 0.5 * n * np.eye(n)  # softened: indefinite
        C = rng.standard_normal((n, 3))
        Ds = C @ C.T  # damping on three directions
        G = rng.standard_normal((n, n))
        G = G - G.T
        N = 0.3 * (C @ rng.standard_normal((3, 3)) @ C.T)
        N = N - N.T  # circulatory, where the damping is
        s = rl.PeriodicSystem(1.0, M={0: M}, D={0: Ds + G}, K={0: K + N})
        radius = energy_radius(s)
        Z = np.zeros((n, n))
        Ainv = np.linalg.solve(M, np.hstack([-(K + N), -(Ds + G)]))
        lam = np.linalg.eigvals(np.vstack([np.hstack([Z, np.eye(n)]), Ainv]))
        outside = lam[np.abs(lam) > radius * (1 + 1e-9)]
        assert np.all(outside.real <= 1e-9 * np.abs(outside))


def test_hidden_high_frequency_instability_is_never_called_stable() -> None:
    """A damped 12-DOF chain with a light oscillator at 2e4 rad/s pumped at twice its frequency
    (Mathieu, inside its first band: the monodromy matrix says unstable) and a band of 10
    modes that leaves it out: the verdict is unstable or undecided, never a decided stable."""
    n = 12
    s0 = mesh_chain(n, asymmetry=0.0)
    wh = 2e4
    K = {
        k: np.asarray(v.toarray() if hasattr(v, "toarray") else v)
        for k, v in s0.K.items()
        if k >= 0
    }
    K0 = K[0].copy()
    K0[-1, :] = K0[:, -1] = 0.0
    K0[-1, -1] = wh**2
    K[0] = K0
    pump = np.zeros((n, n))
    pump[-1, -1] = 0.2 * wh**2  # well inside the first band
    w1 = 2 * wh / 23.0  # 23 w1 = 2 wh: the mesh harmonic pumps it
    K[23] = K[23] + pump
    D0 = s0.D[0].toarray()
    D0[-1, :] = D0[:, -1] = 0.0
    D0[-1, -1] = 2 * 1e-4 * wh
    s = rl.PeriodicSystem(w1, M=s0.M, D={0: D0}, K=K)
    assert _monodromy_max_real(s, rtol=1e-8) > 0
    res = rl.floquet(s, band=10)
    assert not (res.decided and res.stable)


def test_the_reported_seconds_include_the_band(monkeypatch) -> None:
    """``info["seconds"]`` (the run's ``floquet_seconds``) is the whole verdict: the band's
    modes and its scan too, which at 19,998 DOF are half of it (it reported 124 s of about
    270). The band is made to take 0.5 s longer than it does."""
    from rheolin.floquet import large

    real = large.certified_band

    def slow(*args, **kwargs):  # type: ignore[no-untyped-def]
        start = time.perf_counter()
        out = real(*args, **kwargs)
        while time.perf_counter() - start < 0.5:
            time.sleep(0.05)
        return out

    s = mesh_chain(30)
    fast = rl.floquet(s, band=10)
    monkeypatch.setattr(large, "certified_band", slow)
    res = rl.floquet(s, band=10)
    assert res.info["seconds"] >= 0.5
    assert res.info["seconds"] >= fast.info["seconds"]


@pytest.mark.parametrize(
    "error",
    [
        RuntimeError("ARPACK error -1: No convergence (361 iterations)"),
        ValueError("the time-averaged stiffness is singular at every shift tried"),
        MemoryBudgetError("the band method needs an estimated 9.1 GB"),
    ],
)
def test_solve_default_stability_never_raises(monkeypatch, error: Exception) -> None:
    """``rl.solve`` with its default stability check: a Floquet check that fails (an
    eigensolver that does not converge, a singular factorization, the memory budget) leaves
    the verdict "not checked" with the reason; the steady state stands (its residual against
    the harmonic-balance operator recomputed) and nothing is raised. A model past the dense
    limit gets its verdict through ``rl.solve`` in ``test_cli_run_decides_the_fine_rotor``."""
    import importlib

    solve_module = importlib.import_module("rheolin.solvers.solve")

    def failing(*args: object, **kwargs: object) -> None:
        raise error

    monkeypatch.setattr(solve_module, "floquet", failing)
    s = mesh_chain(30)
    with np.errstate(under="ignore"):
        sol = rl.solve(s, rl.HarmonicSet.closure(s, order=1))
    assert sol.floquet is None and sol.stable is None
    assert f"stability not checked: {error}" in sol.message
    assert sol.success and sol.residual < 1e-8, sol.message


def _run(args: list[str], env_budget: str | None = None) -> subprocess.CompletedProcess:
    import os

    env = dict(os.environ)
    if env_budget is not None:
        env["RHEOLIN_MEMORY_BUDGET"] = env_budget
    return subprocess.run(
        [sys.executable, "-m", "rheolin.cli", *args], capture_output=True, text=True, env=env
    )


def test_cli_run_decides_the_fine_rotor(tmp_path: Path) -> None:
    """``rheolin run`` on the rotor past the dense limit (335 shaft nodes, 2,010 DOF) with
    default options: a decided stable verdict at 3000 rpm (exit 0, summary.json written; the
    largest real part negative, as the 3-node model's). The unstable speed and the 401-node
    model run in bench/large_stability.py; the verdicts are checked in process above."""
    import json

    model = tmp_path / "fine.toml"
    model.write_text(refined_example("rotor", 335))
    out = tmp_path / "3000rpm"
    done = _run(["run", str(model), "--speed", "3000rpm", "--out", str(out), "--no-plots"])
    assert done.returncode == 0, done.stdout + done.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stability"] == "stable" and summary["stability_decided"] is True
    assert summary["n_dof"] == 2010 and summary["max_floquet_real"] < 0


def test_cli_refuses_a_model_too_large_for_the_band_method(tmp_path: Path) -> None:
    """``--stability on`` with a memory budget the band method cannot meet: exit 2 before
    anything runs, with the estimate and what to change."""
    model = tmp_path / "fine.toml"
    model.write_text(refined_example("rotor", 335))
    done = _run(
        ["run", str(model), "--stability", "on", "--out", str(tmp_path / "o"), "--no-plots"],
        env_budget="20 MB",
    )
    assert done.returncode == 2, done.stdout + done.stderr
    text = done.stdout + done.stderr
    assert "estimated" in text and "RHEOLIN_MEMORY_BUDGET" in text
    assert not (tmp_path / "o" / "results.nc").exists()


def test_a_finer_order_past_the_budget_is_a_note_not_an_error(monkeypatch) -> None:
    """Raising the lattice order of an undecided band verdict checks the finer lattice with
    the band's memory, as the search itself does: past the budget the verdict stays
    undecided with a note naming the estimate (the 100,026-DOF gearbox with a 20 GB budget
    raised MemoryBudgetError, 24.8 GB for order 2 with its band, from ``rl.floquet``)."""
    from rheolin.floquet import lattice_run

    calls: list[int] = []

    class Undecided:
        decided, stable = False, True

        def __init__(self) -> None:
            self.info: dict = {"seconds": 0.0}

    def search(system, lattice, **kwargs):  # the order-1 verdict, then the real budget check
        calls.append(lattice.order)
        if len(calls) > 1:
            raise MemoryBudgetError("the finer lattice with its band does not fit")
        return Undecided()

    monkeypatch.setattr(lattice_run, "floquet_on_lattice", search)
    monkeypatch.setattr(lattice_run.large, "band_failed", lambda modes: False)
    monkeypatch.setattr(lattice_run, "band_memory", lambda system, modes: 10**15)
    system = _assembled(refined_example("rotor", 335), 3000.0).system
    res = lattice_run.lattice_auto(system, None, None, refine=True)
    assert calls == [1]
    assert "order 2" in res.info["note"] and "memory budget" in res.info["note"]


def test_band_lattice_past_the_budget_is_refused_before_the_scan(monkeypatch) -> None:
    """The lattice a band's modes ask for (resonant costs) can be larger than the first
    estimate's: the 50,022-DOF gearbox is admitted at 3.2 GB and refused at 6.3 GB. The last
    band it can grow to (here: a band of 40 modes asked for) is checked with its own lattice
    before its scan: a search that does not fit is refused, and the scan never runs."""
    import importlib

    band = importlib.import_module("rheolin.floquet.band")
    large = importlib.import_module("rheolin.floquet.large")
    resonance = importlib.import_module("rheolin.floquet.resonance")
    system = _assembled(refined_example("rotor", 335), 3000.0).system
    upfront = large.band_estimate(system, 1)
    lattice = resonance.floquet_lattice

    def resonant(system, order, **kwargs):  # the band's modes ask for two orders more
        return lattice(system, order + 2, **kwargs)

    scans: list[int] = []
    certify = band.certify
    monkeypatch.setattr(band, "certify", lambda *a, **k: scans.append(1) or certify(*a, **k))
    monkeypatch.setattr(resonance, "floquet_lattice", resonant)
    with pytest.raises(MemoryBudgetError, match=r"band modes.*lattice search of order 1"):
        large.certified_band(system, 40, int(1.01 * upfront), 1)
    assert scans == []
    monkeypatch.setattr(resonance, "floquet_lattice", lattice)  # the band's own lattice fits
    modes = large.certified_band(system, None, 10 * upfront, 1)
    assert scans and modes.complement is not None
