"""The Radau monodromy reference of monodromy.py against independent answers: Mathieu's band
edges (SciPy's characteristic values), DOP853 monodromy matrices of small systems with every
coefficient varying, and the stored gearbox-variant references (their file and its command).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.special import mathieu_a, mathieu_b

import rheolin as rl

sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).parents[1] / "core"))
from gear_variants import BRACKETS, POINTS, reference_ranges
from monodromy import leading_real
from test_lattice import chain, mathieu, monodromy_max_real


@pytest.mark.parametrize("edge", ["a1", "b1"])
def test_damped_mathieu_band_edge_is_the_damping(edge: str) -> None:
    """``y = exp(-z t) u`` turns ``y'' + 2 z y' + (a - 2 q cos 2t) y = 0`` into Mathieu's
    equation with ``a - z^2``: on the first band's edges ``a - z^2 = a_1(q)`` or ``b_1(q)``
    the undamped exponent is 0 (a double multiplier), so the largest real part is ``-z``."""
    q, z = 0.8, 0.05
    char = mathieu_a(1, q) if edge == "a1" else mathieu_b(1, q)
    ref = leading_real(mathieu(char + z * z, q, z), steps=400)
    # a double multiplier: an error e of the matrix moves it by sqrt(e)
    assert ref.value == pytest.approx(-z, abs=2e-5)


def test_inside_the_mathieu_band_against_dop853() -> None:
    s = mathieu(1.0, 0.3, 0.05)
    ref = leading_real(s, steps=400)
    assert ref.value == pytest.approx(monodromy_max_real(s), rel=1e-9)
    assert ref.error < 1e-8


def test_two_mesh_chain_against_dop853() -> None:
    """The combination resonance of ``test_lattice.chain`` (3 DOFs, two mesh harmonics)."""
    from test_lattice import _w_gear

    s = chain(2 * _w_gear() / 8.03, 0.3, 0.3)
    ref = leading_real(s, steps=800)
    assert ref.value > 1.0
    assert ref.value == pytest.approx(monodromy_max_real(s), rel=1e-7)


def test_varying_mass_damping_and_stiffness_against_dop853() -> None:
    """Every coefficient time-periodic (two harmonics each, on some DOFs only): the
    monodromy's low-rank stage solve (the varying DOFs) and its mass term against DOP853."""
    rng = np.random.default_rng(3)
    n = 4
    A = rng.standard_normal((n, n))
    M0 = np.eye(n) + 0.1 * (A @ A.T)
    K0 = np.diag([4.0, 9.0, 16.0, 25.0]) + 0.2 * (A + A.T)
    D0 = 0.05 * np.eye(n) + 0.1 * np.outer(A[0], A[0])
    sel = np.zeros((n, n))
    sel[np.ix_([0, 2], [0, 2])] = 1.0

    def var(scale: float) -> dict[int, np.ndarray]:
        return {
            k: scale * sel * (rng.standard_normal((n, n)) + 1j * rng.standard_normal((n, n)))
            for k in (1, 2)
        }

    M = {0: M0, **var(0.05)}
    D = {0: D0, **var(0.02)}
    K = {0: K0, **var(1.0)}
    for k in (1, 2):  # symmetric real coefficient matrices in time: X_-k = conj(X_k)
        for table in (M, D, K):
            table[k] = 0.5 * (table[k] + table[k].T)
    s = rl.PeriodicSystem(2.3, M=M, D=D, K=K)
    ref = leading_real(s, steps=800)
    assert ref.value == pytest.approx(monodromy_max_real(s), rel=1e-7, abs=1e-9)


def test_stored_gear_variant_references() -> None:
    """The stored file holds both ranges inside their brackets, with bounds known to 1e-6
    relative, and the largest real parts at the listed speeds (unstable inside the ranges)
    known to 1e-4 1/s (their change when the step is halved)."""
    data = reference_ranges()
    assert "gear_variants.py --regenerate" in data["command"]
    for name, spec in BRACKETS.items():
        found = data["ranges"][name]
        for side in ("lower", "upper"):
            a, b = sorted(spec[side])
            assert a < found[f"{side}_rpm"] < b
            assert found[f"{side}_uncertainty_rpm"] < 1e-6 * found[f"{side}_rpm"]
    stored = {p["rpm"]: p for p in data["points"]}
    assert set(stored) == set(POINTS)
    for rpm, p in stored.items():
        inside = any(
            data["ranges"][r]["lower_rpm"] < rpm < data["ranges"][r]["upper_rpm"] for r in BRACKETS
        )
        assert (p["max_real"] > 0) == inside, rpm
        assert p["error"] < 1e-4
