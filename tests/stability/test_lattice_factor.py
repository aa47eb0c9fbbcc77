"""The lattice operator's SuperLU factors after the first reuse its minimum-degree ordering
(``shift_invert.superlu``): their solves must be those of a dense LU of the same matrix."""

import importlib

import numpy as np
import pytest

from rheolin.data import example_path
from rheolin.harmonics.hill_lattice import LatticeHill
from rheolin.io import load_model

si = importlib.import_module("rheolin.floquet.shift_invert")
resonance = importlib.import_module("rheolin.floquet.resonance")


@pytest.fixture(scope="module")
def gearbox_hill() -> LatticeHill:
    system = load_model(example_path("gearbox")).assemble(3000 * np.pi / 30).system
    lattice = resonance.floquet_lattice(system, 1, max_size=10**6)
    return LatticeHill(system, lattice.indices)


def test_ordered_factors_solve_like_a_dense_lu(gearbox_hill: LatticeHill) -> None:
    hill = gearbox_hill
    rng = np.random.default_rng(3)
    w = hill.w
    # the first shift orders the pattern; the next ones reuse it, including a shift near an
    # averaged exponent of the gearbox (-51 + 2633i 1/s), where pivoting matters most
    shifts = [complex(-300, 5000), complex(-51.2, 2633.0), complex(-2e4, 1e5), 1e-4 * w * (1 + 1j)]
    first = si.factor(hill, shifts[0], w)
    assert not isinstance(first.lu, si.OrderedLU)
    for sigma in shifts:
        lu = si.factor(hill, sigma, w)
        if sigma != shifts[0]:
            assert isinstance(lu.lu, si.OrderedLU)
        Q = hill.Q(lu.sigma).toarray()
        b = rng.standard_normal(Q.shape[0]) + 1j * rng.standard_normal(Q.shape[0])
        for trans, A in (("N", Q), ("H", Q.conj().T)):
            x = lu.solve(b, trans=trans)
            ref = np.linalg.solve(A, b)
            assert np.linalg.norm(x - ref) <= 1e-9 * np.linalg.norm(ref), (sigma, trans)


def test_a_new_pattern_is_ordered_anew(gearbox_hill: LatticeHill) -> None:
    """Another lattice (another pattern) never takes this lattice's ordering."""
    hill = gearbox_hill
    si.factor(hill, complex(-300, 5000), hill.w)
    other = LatticeHill(hill.system, np.array([-437, 0, 437]))
    assert not hill._ordered.ordered.matches(other.Q(0.5j))  # type: ignore[attr-defined]
    lu = si.factor(other, complex(-300, 5000), other.w)
    Q = other.Q(lu.sigma).toarray()
    b = np.ones(Q.shape[0], dtype=complex)
    assert np.allclose(lu.solve(b), np.linalg.solve(Q, b), rtol=1e-9, atol=0)
