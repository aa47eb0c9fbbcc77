"""Honest success: the backward error as the acceptance criterion (stiff ties accepted, checked
against a closed form), undecided and unstable verdicts said, one versioned JSON schema."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import numpy as np

import rheolin as rl


def test_stiff_tie_is_accepted_by_its_backward_error_and_matches_the_closed_form():
    """Two masses tied by 1e13 N/m, the first on a 1e3 N/m spring, forced on the second:
    ||f - A q|| / ||f|| is round-off times 1e13 |q| / |f| (above 1e-10), the backward error
    is round-off. The response is the closed form of the 2-DOF system (Cramer's rule)."""
    m1, m2, kt, kg, c, w, F = 2.0, 3.0, 1e13, 1e3, 5.0, 7.0, 1.0
    M = np.diag([m1, m2])
    K = np.array([[kg + kt, -kt], [-kt, kt]])
    D = np.diag([c, 0.0])
    s = rl.PeriodicSystem(w, M={0: M}, D={0: D}, K={0: K}, f={1: np.array([0.0, F / 2])})
    sol = rl.solve(s, [1], method="lti", stability=False)
    b = kg - w**2 * m1 + 1j * w * c  # det = a11 a22 - kt^2 without cancellation:
    det = kt * (b - w**2 * m2) - b * w**2 * m2
    q1, q2 = kt * (F / 2) / det, (b + kt) * (F / 2) / det
    got = sol.q[list(sol.harmonics).index(1)]
    # forward error <= condition (|A| ~ 1e13 / smallest eigenvalue ~ 1e2) x backward error
    assert np.allclose(got, [q1, q2], rtol=1e-9, atol=0), (got, q1, q2)
    assert sol.success and sol.status == 0, sol.message
    assert sol.residual < 1e-15
    assert sol.info["relative_residual"] > 1e-10  # the old criterion would have refused it


def test_backward_error_matches_its_definition_on_a_dense_operator():
    """The backward error of a perturbed solution against the dense coupled operator,
    assembled here independently: within the factor ||A||_2 / (its upper bound)."""
    from rheolin.harmonics import HarmonicSet
    from rheolin.harmonics.balance import HarmonicBalance

    rng = np.random.default_rng(3)
    n, w = 4, 1.3
    A = rng.standard_normal((n, n))
    K0 = A @ A.T + n * np.eye(n)
    K1 = 0.1 * rng.standard_normal((n, n))
    s = rl.PeriodicSystem(w, M={0: np.eye(n)}, K={0: K0, 1: K1, -1: K1}, f={1: np.ones(n)})
    H = list(range(-3, 4))
    op = HarmonicBalance(s, HarmonicSet(H))
    big = np.zeros((7 * n, 7 * n), complex)
    for i, m in enumerate(H):
        for j, k in enumerate(H):
            blk = {0: K0 - (k * w) ** 2 * np.eye(n), 1: K1, -1: K1}.get(m - k)
            if blk is not None:
                big[i * n : (i + 1) * n, j * n : (j + 1) * n] = blk
    f = np.concatenate([np.ones(n) if abs(k) == 1 else np.zeros(n) for k in H])
    q = np.linalg.solve(big, f)
    q = q + 1e-6 * np.abs(q).max() * np.tile(rng.standard_normal(n), 7)  # real noise
    Q = op.half(q.reshape(7, n))
    assert np.allclose(op.expand(Q).ravel(), q)  # the noise keeps conjugate symmetry
    exact = np.linalg.norm(f - big @ q) / (
        np.linalg.norm(big, 2) * np.linalg.norm(q) + np.linalg.norm(f)
    )
    ratio = np.linalg.norm(big, 2) / op.norm_bound
    got = op.backward_error(Q)
    assert ratio <= 1.0
    assert exact * ratio * (1 - 1e-9) <= got <= exact * (1 + 1e-9)
    assert got <= op.relative_residual(Q)


def test_undecided_verdict_is_said_on_the_console_and_in_summary_json(invoke, rotor, tmp_path):
    """The example rotor with 1e-4 of its bearing damping (0.05 N s/m): the leading Floquet
    real part is about -2e-6 1/s, and exponents near -0.17 1/s have not converged in the
    truncation, their error estimates reaching the axis, so the verdict cannot be decided;
    ``stability_open`` names them, and the command exits 1 (results written)."""
    light = rotor.read_text().replace('"500 N*s/m"', '"0.05 N*s/m"')
    assert light.count('"0.05 N*s/m"') == 5
    rotor.write_text(light)
    res = invoke("run", rotor, "--speed", "1000rpm", "--out", tmp_path / "o", "--no-plots")
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["schema"] == "rheolin.summary" and summary["schema_version"] == 1
    assert summary["success"] is True and summary["stability_decided"] is False
    assert summary["stability"] == "undecided"
    assert "UNDECIDED" in res.stderr and res.exit_code == 1  # not a pass (docs/cli.md)
    # what keeps it open, on the console too: exponents whose truncation error estimate (the
    # number after +-) is larger than their distance to the axis, none above the leading one
    why = summary["stability_open"]
    assert why in " ".join(res.stderr.split())
    named = re.findall(r"([-0-9.e+]+) \+- ([0-9.e+-]+) 1/s at", why)
    assert named, why
    for re_part, reach in ((float(a), float(b)) for a, b in named):
        assert re_part <= summary["max_floquet_real"] < 0 < re_part + reach, (re_part, reach)


def test_sweep_with_stability_off_never_reports_zero_unstable(invoke, tmp_path):
    """A rigid rotor on a spring in its own axes (tests/study/study_cases.py): unstable
    exactly between sqrt(k_x / m) = 100 and sqrt(k_y / m) = 110 rad/s. With the per-point
    check off the map still finds the band, so the summary counts it and exits 1."""
    sys.path.insert(0, str(Path(__file__).parents[1] / "study"))
    from study_cases import BAND

    (tmp_path / "band.toml").write_text(BAND)
    out = tmp_path / "s"
    res = invoke(
        "sweep", tmp_path / "band.toml", "--speeds", "95,105,108,115rad/s",
        "--stability", "off", "--workers", "1", "--no-plots", "--out", out,
    )  # fmt: skip
    assert res.exit_code == 1, res.stdout + res.stderr
    assert "stability (from the map): 2 unstable" in res.stdout
    table = json.loads((out / "sweep.json").read_text())
    assert table["schema"] == "rheolin.sweep" and table["schema_version"] == 1
    assert all(isinstance(x, bool) for x in table["success"])
    lo, hi = table["unstable_ranges_rpm"][0]
    rpm = 30 / np.pi
    assert abs(lo / (100 * rpm) - 1) < 1e-4 and abs(hi / (110 * rpm) - 1) < 1e-4


def test_exponents_on_the_axis_read_stable_whatever_side_round_off_puts_them():
    """An undamped oscillator m x'' + k x = 0: its exponents are +-i sqrt(k / m) exactly, so
    the verdict is stable and marginal; round-off puts the computed real part on either side
    of zero and both read "stable". A real part c / (2 m) above the tolerance (negative
    damping -c) reads "unstable", as FloquetResult.stable says."""
    from dataclasses import replace

    from rheolin.results import stability_text
    from rheolin.results.dataset import leading_tolerance

    m, k = 2.0, 8.0e4
    system = rl.PeriodicSystem(30.0, M={0: np.array([[m]])}, K={0: np.array([[k]])})
    res = rl.floquet(system, 2)
    w0 = np.sqrt(k / m)
    folded = abs(w0 - 30.0 * round(w0 / 30.0))  # +-i w0 folded into (-w1/2, w1/2]
    np.testing.assert_allclose(np.abs(res.exponents.imag), folded, rtol=1e-9)
    tol = leading_tolerance(res)
    assert abs(res.max_real) <= tol < 1e-6 * w0
    assert res.stable and res.decided and res.marginal
    for real in (-0.5 * tol, 0.0, 0.5 * tol, tol):  # round-off of either sign, up to tol
        moved = replace(res, exponents=res.exponents + (real - res.max_real), max_real=real)
        assert leading_tolerance(moved) == tol
        assert stability_text(True, True, real, tol) == "stable"
    assert stability_text(True, True, 2 * tol, tol) == "undecided"
    c = 1e-3 * 2 * m * w0
    lively = rl.PeriodicSystem(30.0, M={0: np.array([[m]])}, D={0: np.array([[-c]])},
                               K={0: np.array([[k]])})  # fmt: skip
    grow = rl.floquet(lively, 2)
    assert abs(grow.max_real - c / (2 * m)) < 1e-9 * w0  # lambda = c/2m +- i w0 sqrt(1-z^2)
    assert not grow.stable
    assert stability_text(grow.stable, grow.decided, grow.max_real, leading_tolerance(grow)) == (
        "unstable"
    )
