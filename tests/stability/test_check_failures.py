"""A stability check that fails numerically (an eigensolver that does not converge, a
singular factorization) leaves that speed undecided, with the reason, and never ends a
stability map, a range edge or a sweep point (issue 31: never an exception from a default).

The failure is injected into the real verdicts of the rigid rotor on a spring fixed in its
own axes, whose unstable band has a closed form (tests/stability/test_stability_map.py):
what is reported around the failure must still match it.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.sparse.linalg import ArpackNoConvergence

from rheolin.mechanics import Model
from rheolin.stability import stability_map

sys.path.insert(0, str(Path(__file__).parent))
from test_stability_map import STIFF, _band

# the modules whose floquet the map calls (loaded with rheolin.stability)
map_module = sys.modules["rheolin.stability.stability_map"]
verdicts_module = sys.modules["rheolin.stability.verdicts"]  # the map's speeds and edges

M, KX, KY, C = 2.0, 4e3, 1.6e4, 15.0
LO, HI = _band(M, KX, KY, C)


def _model() -> Model:
    model = Model()
    model.add_rigid_body("rotor", (0, 0, 0), M, (1e-3, 1e-3, 2e-3))
    model.add_bearing("shaft", "rotor", 0, [KX, KY], components=("ux", "uy"), frame="rotor")
    model.add_bearing("support", "rotor", 0, STIFF, 0.0, components=("uz", "phix", "phiy", "phiz"))
    model.add_bearing("damper", "rotor", 0, 0.0, C, components=("ux", "uy"))
    return model


def _failing(monkeypatch, where) -> None:
    real = map_module.floquet

    def floquet(system, *args, **kwargs):
        if where(system.omega):  # the model's w1 is its speed
            raise ArpackNoConvergence("ARPACK error -1: No convergence", [], [])
        return real(system, *args, **kwargs)

    monkeypatch.setattr(map_module, "floquet", floquet)
    monkeypatch.setattr(verdicts_module, "floquet", floquet)


def test_a_failed_sample_is_undecided_with_its_reason(monkeypatch) -> None:
    speeds = np.linspace(0.5 * LO, 1.5 * HI, 11)
    _failing(monkeypatch, lambda w: abs(w - speeds[1]) < 1e-9)
    smap = stability_map(_model(), speeds, harmonics=4)
    assert smap.state[1] == "undecided" and not smap.stable[1]
    assert "ArpackNoConvergence" in smap.info["failed"][float(speeds[1])]
    (r,) = smap.ranges  # the band itself, from the other speeds, to the closed form
    assert r.lower == pytest.approx(LO, rel=1e-6) and r.upper == pytest.approx(HI, rel=1e-6)


def test_failures_next_to_an_edge_widen_its_uncertainty(monkeypatch) -> None:
    """Every evaluation within 2 % below the lower edge fails: the bound's stated
    uncertainty must still cover the closed form."""
    speeds = np.linspace(0.5 * LO, 1.5 * HI, 11)
    _failing(monkeypatch, lambda w: 0.98 * LO < w < LO and not np.any(np.isclose(w, speeds)))
    smap = stability_map(_model(), speeds, harmonics=4)
    (r,) = smap.ranges
    assert 1e-3 * LO < r.lower_uncertainty < 0.05 * LO  # the failures widened it
    assert abs(r.lower - LO) <= r.lower_uncertainty
    assert r.upper == pytest.approx(HI, rel=1e-6)
