"""HarmonicSet construction and closure (counted by hand), and Solution.evaluate (manual sum)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import rheolin as rl


def _system(coefficient_harmonics: list[int], load_harmonics: list[int]) -> rl.PeriodicSystem:
    K = {0: np.eye(1), **{k: 0.1 * np.eye(1) for k in coefficient_harmonics}}
    return rl.PeriodicSystem(1.0, M={0: np.eye(1)}, K=K, f={k: np.ones(1) for k in load_harmonics})


def test_full_and_symmetrization() -> None:
    assert list(rl.HarmonicSet.full(0)) == [0]
    assert list(rl.HarmonicSet.full(3)) == [-3, -2, -1, 0, 1, 2, 3]
    h = rl.HarmonicSet([5, 2, 2, -5])
    assert list(h) == [-5, -2, 2, 5] and len(h) == 4
    assert list(h.nonnegative) == [2, 5]
    assert 2 in h and -2 in h and 3 not in h
    assert h == rl.HarmonicSet([-2, 5]) and hash(h) == hash(rl.HarmonicSet([-2, 5]))
    assert list(rl.HarmonicSet(np.array([1.0, 3.0]))) == [-3, -1, 1, 3]


@pytest.mark.parametrize("bad", [[], [0.5], ["a"]])
def test_bad_indices(bad: list) -> None:
    with pytest.raises(ValueError, match="`harmonics`"):
        rl.HarmonicSet(bad)


@pytest.mark.parametrize("bad", [-1, 1.0, True, "3"])
def test_bad_full(bad: object) -> None:
    with pytest.raises(ValueError, match="`N`"):
        rl.HarmonicSet.full(bad)  # type: ignore[arg-type]


def test_closure_single_generator_by_hand() -> None:
    """Load ±1, generator 4.
    S0 = {±1};  S1 = S0 ∪ {1±4, -1±4} = {±1, ±3, ±5};  S2 adds 5+4 = 9, 3+4 = 7: {±1,...,±9}."""
    s = _system([4], [1])
    assert list(rl.HarmonicSet.closure(s, order=0)) == [-1, 1]
    assert list(rl.HarmonicSet.closure(s, order=1)) == [-5, -3, -1, 1, 3, 5]
    h2 = rl.HarmonicSet.closure(s, order=2)
    assert list(h2) == [-9, -7, -5, -3, -1, 1, 3, 5, 7, 9]
    assert list(rl.HarmonicSet.closure(s, order=2, max_harmonic=6)) == [-5, -3, -1, 1, 3, 5]


def test_a_cut_off_below_a_load_harmonic_warns() -> None:
    """Loads at 1, 3 and 7 with generator 4: a cut-off of 6 drops the load at 7 (only the
    load at 7 reaches 7 - 4 = 3 at order 1, so the kept harmonics are wrong too); 7 does not."""
    s = _system([4], [1, 3, 7])
    with pytest.warns(rl.TruncationWarning, match=r"leaves out 1 of 3 load harmonics \(7\)"):
        h = rl.HarmonicSet.closure(s, order=1, max_harmonic=6)
    assert 7 not in h and 3 in h
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert 7 in rl.HarmonicSet.closure(s, order=1, max_harmonic=7)
        rl.HarmonicSet.closure(s, order=1)


def test_closure_two_generators_by_hand() -> None:
    """Load ±1, generators 2 and 5 (e.g. an asymmetric body at 2W and a 5-tooth mesh).

    order 1: 1±2 = {3, -1}, 1±5 = {6, -4}            -> {±1, ±3, ±4, ±6}              (8)
    order 2: 3±2 = {5, 1}, 3±5 = {8, -2}, 4±2 = {6, 2}, 4±5 = {9, -1}, 6±2 = {8, 4},
             6±5 = {11, 1}                            -> adds ±2, ±5, ±8, ±9, ±11       (18)
    cut at 8:                                         -> {±1, ±2, ±3, ±4, ±5, ±6, ±8}   (14)
    """
    s = _system([2, 5], [1])
    assert len(rl.HarmonicSet.closure(s, order=1)) == 8
    h2 = rl.HarmonicSet.closure(s, order=2)
    assert list(h2.nonnegative) == [1, 2, 3, 4, 5, 6, 8, 9, 11]
    assert len(h2) == 18
    cut = rl.HarmonicSet.closure(s, order=2, max_harmonic=8)
    assert list(cut.nonnegative) == [1, 2, 3, 4, 5, 6, 8] and len(cut) == 14
    # explicit generators override the system's coefficient harmonics
    only2 = rl.HarmonicSet.closure(s, order=2, generators=[2])
    assert list(only2.nonnegative) == [1, 3, 5]


def test_closure_static_load() -> None:
    """Gravity (f_0) on an asymmetric rotor (K_{±2}): {0, ±2, ±4, ±6} after three steps."""
    s = _system([2], [0])
    assert list(rl.HarmonicSet.closure(s, order=3)) == [-6, -4, -2, 0, 2, 4, 6]


def test_closure_errors() -> None:
    s = _system([2], [1])
    with pytest.raises(ValueError, match="`order`"):
        rl.HarmonicSet.closure(s, order=-1)
    with pytest.raises(ValueError, match="`max_harmonic`"):
        rl.HarmonicSet.closure(s, order=1, max_harmonic=-2)
    with pytest.raises(ValueError, match="`max_harmonic`"):
        rl.HarmonicSet.closure(_system([2], [3]), order=1, max_harmonic=2)
    no_load = rl.PeriodicSystem(1.0, M={0: np.eye(1)}, K={0: np.eye(1)})
    with pytest.raises(ValueError, match="load"):
        rl.HarmonicSet.closure(no_load)


def test_closure_solution_matches_dense_set() -> None:
    """A closure set holds exactly the harmonics the dense set excites: on the asymmetric rotor
    with unbalance and gravity, the dense -8..8 solution is zero outside the closure."""
    from cases import assembled_reference, gravity_rotor

    rotor = gravity_rotor(unbalance=True, W_ratio=0.3)
    system = rotor.system()
    closed = rl.HarmonicSet.closure(system, order=4)
    assert list(closed.nonnegative) == [0, 1, 2, 3, 4, 5, 6, 7, 8, 9]
    H = rl.HarmonicSet.full(9).indices
    ref = assembled_reference(rotor.W, *rotor.coefficients(), H)
    sol = rl.solve(system, closed, method="gmres")
    np.testing.assert_allclose(sol.q, ref, rtol=0, atol=1e-9 * abs(ref).max())


def test_solution_evaluate_and_harmonic() -> None:
    q = np.array([[1 - 2j, 0.5], [3.0, -1.0], [1 + 2j, 0.5]])
    sol = rl.Solution(
        harmonics=np.array([-2, 0, 2]),
        q=q,
        omega=1.3,
        success=True,
        status=0,
        message="",
        method="x",
    )
    t = np.linspace(-1.0, 7.0, 11)
    # manual: q_0 + 2 Re(q_2 e^{2 i w t})
    manual = np.array([q[1].real + 2 * (q[2] * np.exp(2j * 1.3 * tt)).real for tt in t])
    np.testing.assert_allclose(sol.evaluate(t), manual, atol=1e-14)
    at = q[1].real + 2 * (q[2] * np.exp(2j * 1.3 * 0.4)).real
    np.testing.assert_allclose(sol.evaluate(0.4), at[None, :], atol=1e-14)  # scalar t
    assert sol.evaluate(t).shape == (11, 2)
    np.testing.assert_array_equal(sol.harmonic(2), q[2])
    with pytest.raises(KeyError):
        sol.harmonic(1)
