"""The ``transient`` method (BDF from rest, periodic-steady-state detector) against harmonic
balance.

Truth is the frequency domain: ``gmres`` / ``direct`` at ``rtol = 1e-12`` on the same harmonic
set, which ``test_time_domain.py`` and ``test_solvers.py`` validate against an independent time
integration and closed forms. The transient solver shares nothing with them but the
``PeriodicSystem`` (its own time evaluation of ``M(t), D(t), K(t), f(t)``, its own DFT).

Tolerances: BDF at ``rtol = 1e-8`` (small systems) or ``1e-7`` (geared model) leaves a global
error of order 1e-7 of the response; the detector stops at a period-to-period change of 1e-7,
and the harmonic truncation of the reference is below 1e-10 for the small systems (coefficients
decay geometrically); for the geared model the reference runs on a wider set (``max_harmonic =
300``; truncating it at 90 would move it by 9e-6) and is compared on the transient's set. Hence
2e-6 relative (max over all harmonics and DOFs, scaled by the largest coefficient); a
convention error (sign, factor 2, conjugate) is ~1e-2..1.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from test_time_domain import varying_2dof, varying_3dof

import rheolin as rl
import rheolin.solvers.transient.settings as tr
from rheolin.mechanics import Model

BACKENDS = [
    "scipy",
    pytest.param(
        "sundae",
        marks=pytest.mark.skipif(not tr.sundae_available(), reason="scikit-sundae not installed"),
    ),
]


def _rel(sol: rl.Solution, ref: rl.Solution) -> float:
    assert np.array_equal(sol.harmonics, ref.harmonics)
    return float(np.abs(sol.q - ref.q).max() / np.abs(ref.q).max())


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("case", [varying_2dof, varying_3dof], ids=["2dof_MDK", "3dof_mesh"])
@pytest.mark.parametrize("sparse", [False, True], ids=["dense", "sparse"])
def test_time_varying_M_D_K_agree_with_harmonic_balance(
    case: Callable[[], Any], backend: str, sparse: bool
) -> None:
    """M, D and K all time-varying (the mass at w or 2w, a rank-1 mesh-like stiffness)."""
    if sparse and backend == "sundae":
        pytest.skip("the sundae backend reads the same coefficient tables for both storages")
    system = case().system(sparse=sparse)
    ref = rl.solve(system, 20, method="direct", stability=False)
    assert ref.success
    sol = rl.solve(
        system,
        20,
        method="transient",
        stability=False,
        options={"backend": backend, "rtol": 1e-8, "period_tol": 1e-7},
    )
    assert sol.success and sol.status == 0, sol.message
    assert sol.method == "transient"
    assert sol.iterations == sol.info["periods"] >= 2
    assert sol.info["steps"] > 0 and sol.info["backend"] == backend
    assert sol.history[-1] <= 1e-7
    print(f"transient vs direct: {_rel(sol, ref):.2e}")
    assert _rel(sol, ref) < 2e-6, _rel(sol, ref)


def geared_model() -> Model:
    """A spur pair on elastic bearings (6 + 9 teeth: spins 3 and -2, mesh harmonic 18), a
    rectangular-wave mesh stiffness, unbalance and transmission error: M, D, K time-varying."""
    model = Model()
    model.add_rigid_body("pinion", (0, 0, 0), 1.0, (5e-4, 5e-4, 4e-4))
    model.add_rigid_body("gear", (0.03, 0, 0), 2.0, (1.5e-3, 1.5e-3, 1.2e-3))
    model.add_disk("pinion", 0, unbalance=2e-5, unbalance_angle=0.3)
    model.add_disk("gear", 0, unbalance=4e-5, unbalance_angle=-1.0, couple_unbalance=2e-6)
    for body in ("pinion", "gear"):
        model.add_bearing(
            body + "_bearing",
            body,
            0,
            [1e6, 1e6, 1e6, 2e3, 2e3, 50.0],
            [400.0, 400.0, 400.0, 0.4, 0.4, 0.1],
            components=None,
        )
    model.add_gear_mesh(
        "mesh",
        "pinion",
        0,
        "gear",
        0,
        6,
        9,
        module=4e-3,
        helix_angle=np.radians(12),
        contact_ratio=1.6,
        single_stiffness=1.6e6,
        double_stiffness=2.4e6,
        stiffness_harmonics=2,
        damping=450.0,
        transmission_error={1: 2e-6, 2: 0.5e-6j},
    )
    return model


@pytest.mark.parametrize("backend", BACKENDS)
def test_geared_model_agrees_with_harmonic_balance(backend: str) -> None:
    a = geared_model().assemble(speed=100.0)
    system = a.system
    assert a.plan.mesh == (18,) and system.M.keys() - {0}  # the mass varies too (unbalance)
    H = rl.HarmonicSet.closure(system, order=40, max_harmonic=90, generators=a.generators)
    # the reference on a wider set: truncating it at 90 alone would differ by 9e-6
    wide = rl.HarmonicSet.closure(system, order=80, max_harmonic=300, generators=a.generators)
    ref = rl.solve(system, wide, method="gmres", rtol=1e-12, stability=False)
    assert ref.success
    sol = rl.solve(
        system,
        H,
        method="transient",
        stability=False,
        options={"backend": backend, "rtol": 1e-8},  # default period_tol: 10 rtol
    )
    assert sol.success, sol.message
    scale = np.abs(ref.q).max()
    err = max(np.abs(sol.harmonic(n) - ref.harmonic(n)).max() for n in H) / scale
    print(f"transient vs gmres: {err:.2e}")
    assert err < 2e-6, err
    # the dominant harmonics (unbalance at the spins, the mesh) agree as well
    for n in (2, 3, 18):
        e = np.abs(sol.harmonic(n) - ref.harmonic(n)).max() / np.abs(ref.harmonic(n)).max()
        assert e < 1e-5, (n, e)


def test_detector_stops_on_a_decaying_system() -> None:
    """A damped oscillator under harmonic load: the change between periods falls
    geometrically (by the decay factor per period) and the run stops long before the cap."""
    zeta, wn, w = 0.05, 2.0, 1.0
    system = rl.PeriodicSystem(
        w,
        M={0: np.eye(1)},
        D={0: 2 * zeta * wn * np.eye(1)},
        K={0: wn**2 * np.eye(1)},
        f={1: np.ones(1)},
    )
    seen: list[tuple[int, float]] = []
    sol = rl.solve(
        system,
        3,
        method="transient",
        stability=False,
        callback=lambda p, c: seen.append((p, c)),
        options={"backend": "scipy", "max_periods": 200, "period_tol": 1e-6},
    )
    assert sol.success and sol.status == 0, sol.message
    decay = np.exp(-zeta * wn * 2 * np.pi / w)  # free-vibration decay per period
    expected = int(np.ceil(np.log(1e-6) / np.log(decay))) + 2
    assert sol.iterations <= expected + 3 and sol.iterations < 200
    assert [p for p, _ in seen] == list(range(2, sol.iterations + 1))
    assert sol.history == [c for _, c in seen]
    ratios = np.array(sol.history[2:]) / np.array(sol.history[1:-1])
    assert np.allclose(ratios, decay, rtol=0.3), ratios
    exact = 1.0 / (wn**2 - w**2 + 2j * zeta * wn * w)  # closed form q_1 (f_1 = 1)
    assert abs(sol.harmonic(1)[0] - exact) < 1e-5 * abs(exact)


def test_detector_reports_the_cap_on_an_undamped_resonance() -> None:
    """Undamped oscillator forced at its natural frequency: the amplitude grows linearly,
    no period repeats the previous one, and the run ends at the cap with a clear message."""
    system = rl.PeriodicSystem(1.0, M={0: np.eye(1)}, K={0: np.eye(1)}, f={1: np.ones(1)})
    sol = rl.solve(system, 1, method="transient", stability=False, options={"max_periods": 12})
    assert not sol.success and sol.status == 1
    assert "max_periods=12" in sol.message and "cap" in sol.message
    assert sol.iterations == 12 and len(sol.history) == 11
    # the change per period ~ 1/p: growing amplitude, not a steady state
    assert sol.history[-1] > 0.05


def _forced_2dof() -> rl.PeriodicSystem:
    """Damped 2-DOF with a stiffness varying at w1 and a load at w1 (decays by 0.53/period)."""
    zeta, wn = 0.05, 2.0
    return rl.PeriodicSystem(
        1.0,
        M={0: np.eye(2)},
        D={0: 2 * zeta * wn * np.eye(2)},
        K={0: wn**2 * np.eye(2), 1: 0.3 * np.array([[1.0, 0.5], [0.5, 0.0]])},
        f={1: np.ones(2)},
    )


@pytest.mark.parametrize("backend", BACKENDS)
def test_detector_reports_a_stall_at_the_integrator_noise(backend: str) -> None:
    """``period_tol`` far below what ``rtol`` resolves: the change between periods falls
    geometrically until the integration error of each period dominates, then wanders at that
    level. The run stops there (status 1, "stalled"), long before the cap, instead of
    integrating up to ``max_periods``; the returned harmonics are still those of ``rtol``."""
    system = _forced_2dof()
    ref = rl.solve(system, 8, method="direct", stability=False)
    rtol = 1e-5
    sol = rl.solve(
        system,
        8,
        method="transient",
        stability=False,
        options={"backend": backend, "rtol": rtol, "period_tol": 1e-10, "max_periods": 300},
    )
    assert not sol.success and sol.status == 1
    assert "stalled" in sol.message and "rtol=1e-05" in sol.message, sol.message
    # geometric decay 0.53 per period from ~1 reaches 1e-4 in ~15 periods; then the window
    decay_periods = int(np.ceil(np.log(100 * rtol) / np.log(np.exp(-0.2 * np.pi))))
    assert sol.iterations <= decay_periods + 2 * tr.STALL_WINDOW + 5 < 300, sol.iterations
    assert 1e-3 * rtol < sol.history[-1] <= tr.STALL_NOISE * rtol
    assert _rel(sol, ref) < 1e-3  # the answer at the accuracy rtol gives


def test_default_period_tol_follows_rtol() -> None:
    """Without ``period_tol``, a coarse ``rtol`` stops at ``10 rtol`` instead of stalling."""
    system = _forced_2dof()
    ref = rl.solve(system, 8, method="direct", stability=False)
    sol = rl.solve(
        system,
        8,
        method="transient",
        stability=False,
        options={"backend": "scipy", "rtol": 1e-5},
    )
    assert sol.success, sol.message
    assert "period_tol=0.0001" in sol.message and sol.history[-1] <= 1e-4
    assert _rel(sol, ref) < 2e-3
    fine = rl.solve(system, 8, method="transient", stability=False, options={"backend": "scipy"})
    assert "period_tol=1e-06" in fine.message and _rel(fine, ref) < 1e-5


def test_shortest_repeating_period_is_used() -> None:
    """Only even harmonics: the response repeats every pi / w1; the answer is unchanged and
    a longer comparison window (a multiple, through ``period``) gives the same result."""
    s = varying_2dof().system()
    even = rl.PeriodicSystem(
        s.omega,
        M={0: s.M[0]},
        D={0: s.D[0], 2: s.D[2]},
        K={0: s.K[0], 2: s.K[2]},
        f={2: np.array([1.0, 0.5])},
    )
    assert tr.repeat_divisor(even) == 2
    ref = rl.solve(even, 16, method="direct", stability=False)
    sol = rl.solve(even, 16, method="transient", stability=False, options={"backend": "scipy"})
    assert sol.success and np.isclose(sol.info["period"], np.pi / s.omega)
    assert _rel(sol, ref) < 1e-5
    assert np.abs(sol.q[sol.harmonics % 2 == 1]).max() == 0.0
    longer = rl.solve(
        even,
        16,
        method="transient",
        stability=False,
        options={"backend": "scipy", "period": 2 * np.pi / s.omega},
    )
    assert longer.success and np.isclose(longer.info["period"], 2 * np.pi / s.omega)
    assert _rel(longer, ref) < 1e-5


def test_options_are_validated() -> None:
    s = varying_2dof().system()
    with pytest.raises(ValueError, match="unknown transient option"):
        rl.solve(s, 5, method="transient", options={"tolerance": 1e-3})
    with pytest.raises(ValueError, match="`samples` must be an integer >= 21"):
        rl.solve(s, 10, method="transient", options={"samples": 12})
    with pytest.raises(ValueError, match="`period` must be a positive integer multiple"):
        rl.solve(s, 5, method="transient", options={"period": 1.0})
    with pytest.raises(ValueError, match="`backend`"):
        rl.solve(s, 5, method="transient", options={"backend": "cvode"})
    with pytest.raises(ValueError, match="`max_periods`"):
        rl.solve(s, 5, method="transient", options={"max_periods": 1})


def test_singular_mass_is_reported() -> None:
    system = rl.PeriodicSystem(
        1.0,
        M={0: np.diag([1.0, 0.0])},
        D={0: np.eye(2)},
        K={0: 2 * np.eye(2)},
        f={1: np.ones(2)},
    )
    sol = rl.solve(system, 2, method="transient", stability=False, options={"backend": "scipy"})
    assert not sol.success and sol.status == 3 and "mass matrix is singular" in sol.message
