"""Shared test setup: a non-interactive plotting backend and floating-point errors as exceptions."""

from __future__ import annotations

import numpy as np
import pytest

try:  # plotting is optional; never open a window from a test
    import matplotlib

    matplotlib.use("Agg")
except ImportError:  # pragma: no cover - depends on the environment
    pass


@pytest.fixture(autouse=True)
def _raise_on_floating_point_errors():
    """Overflow, invalid operations, division by zero and underflow raise inside every test."""
    old = np.seterr(all="raise")
    try:
        yield
    finally:
        np.seterr(**old)
