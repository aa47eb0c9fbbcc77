"""PeriodicSystem: Fourier-coefficient conventions against closed-form time functions, and
input errors that name the offending argument."""

from __future__ import annotations

import re

import numpy as np
import pytest
import scipy.sparse as sp

import rheolin as rl
from rheolin.errors import ModelError


def test_cosine_and_sine_conventions() -> None:
    """``F cos(w t)`` has ``f_{±1} = F/2``; ``X(t) = sum_k X_k e^{i k w t}`` is real."""
    w = 1.7
    A, B = np.array([[2.0, 0.3], [0.3, 1.0]]), np.array([[0.1, -0.4], [0.2, 0.5]])
    # K(t) = K0 + A cos(w t) + B sin(2 w t):  K_1 = A/2,  K_2 = B/(2i)
    K0 = np.array([[5.0, -1.0], [-1.0, 4.0]])
    F = np.array([1.0, -2.0])
    s = rl.PeriodicSystem(w, M={0: np.eye(2)}, K={0: K0, 1: A / 2, 2: B / 2j}, f={1: F / 2})
    for t in np.linspace(0.0, 2 * np.pi / w, 7):
        np.testing.assert_allclose(
            s.evaluate("K", t), K0 + A * np.cos(w * t) + B * np.sin(2 * w * t), atol=1e-14
        )
        np.testing.assert_allclose(s.evaluate("f", t), F * np.cos(w * t), atol=1e-14)
        np.testing.assert_allclose(s.evaluate("M", t), np.eye(2), atol=0)


def test_negative_harmonics_are_filled_as_conjugates() -> None:
    K1 = np.array([[1 + 2j, 0.5j], [3.0, -1j]])
    s = rl.PeriodicSystem(1.0, M={0: np.eye(2)}, K={0: np.eye(2), 1: K1}, f={2: np.array([1j, 2])})
    np.testing.assert_array_equal(s.K[-1], np.conj(K1))
    np.testing.assert_array_equal(s.f[-2], np.array([-1j, 2]))
    assert s.coefficient_harmonics == [-1, 1]
    assert s.load_harmonics == [-2, 2]
    assert not s.time_invariant
    # given only the negative one, the positive one is filled
    s2 = rl.PeriodicSystem(1.0, M={0: np.eye(2)}, K={0: np.eye(2), -1: np.conj(K1)})
    np.testing.assert_array_equal(s2.K[1], K1)
    # both given and consistent: accepted
    rl.PeriodicSystem(1.0, M={0: np.eye(2)}, K={0: np.eye(2), 1: K1, -1: np.conj(K1)})


def test_properties_and_sparse_input() -> None:
    K0 = sp.diags([2.0, 3.0, 4.0], format="csr")
    s = rl.PeriodicSystem(2.0, M={0: sp.identity(3, format="csr")}, K={0: K0}, f={0: np.ones(3)})
    assert s.n == 3 and s.is_sparse and s.time_invariant
    assert s.load_harmonics == [0]
    assert s.coefficient("K", 0) is not None and s.coefficient("D", 0) is None
    np.testing.assert_array_equal(s.evaluate("K", 0.3), np.diag([2.0, 3.0, 4.0]))
    with pytest.raises(ValueError, match="`name`"):
        s.coefficient("X", 0)
    # zero coefficients are dropped; a complex k=0 with a round-off imaginary part is accepted
    s3 = rl.PeriodicSystem(
        1.0, M={0: np.eye(1) + 1e-17j}, K={0: np.eye(1), 3: np.zeros((1, 1))}, f={1: [0.0]}
    )
    assert s3.time_invariant and s3.load_harmonics == [] and s3.M[0].dtype == float


def test_scalar_system() -> None:
    s = rl.PeriodicSystem(1.0, M={0: 1.0}, K={0: 2.0}, f={1: 1.0})
    assert s.n == 1 and s.K[0].shape == (1, 1)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"omega": 0.0}, "`omega`"),
        ({"omega": -1.0}, "`omega`"),
        ({"omega": np.nan}, "`omega`"),
        ({"omega": "fast"}, "`omega`"),
        ({"K": {0: np.eye(2), 1: np.ones((3, 3))}}, "`K[1]`"),
        ({"K": {0: np.eye(2)}, "M": {0: np.eye(3)}}, "`K[0]` must have shape (3, 3)"),
        ({"f": {1: np.ones(3)}}, "`f[1]`"),
        ({"D": {0: np.array([[np.nan, 0.0], [0.0, 1.0]])}}, "`D[0]` contains NaN"),
        ({"K": {0: np.eye(2), 2: np.full((2, 2), np.inf)}}, "`K[2]` contains NaN or inf"),
        ({"f": {1: np.array([np.nan, 1.0])}}, "`f[1]` contains NaN"),
        ({"K": {0: sp.csr_array(np.array([[np.nan, 0], [0, 1.0]]))}}, "`K[0]` contains NaN"),
        ({"K": {0: np.eye(2), 1: np.eye(2), -1: 2 * np.eye(2)}}, "`K[-1]` must equal conj"),
        ({"K": {0: np.eye(2), 1: 1j * np.eye(2), -1: 1j * np.eye(2)}}, "`K[-1]` must equal conj"),
        ({"f": {1: np.ones(2), -1: -np.ones(2)}}, "`f[-1]` must equal conj"),
        ({"K": {0: 1j * np.eye(2)}}, "`K[0]` must be real"),
        ({"f": {0: np.array([1.0, 1j])}}, "`f[0]` must be real"),
        ({"K": {0.5: np.eye(2)}}, "`K` keys must be integer"),
        ({"K": {0: np.array([["a", "b"], ["c", "d"]])}}, "`K[0]` must be numeric"),
        ({"K": [np.eye(2)]}, "`K` must be a dict"),
    ],
)
def test_bad_input_names_the_argument(kwargs: dict, match: str) -> None:
    base = {"omega": 1.0, "M": {0: np.eye(2)}, "K": {0: np.eye(2)}}
    with pytest.raises(ModelError, match=re.escape(match)):
        rl.PeriodicSystem(**{**base, **kwargs})


def test_all_zero_and_empty_systems_are_refused() -> None:
    with pytest.raises(ModelError, match="all zero"):
        rl.PeriodicSystem(1.0, M={0: np.zeros((2, 2))}, K={0: np.zeros((2, 2))})
    with pytest.raises(ModelError, match="M, D, K"):
        rl.PeriodicSystem(1.0)
    assert issubclass(ModelError, ValueError)
