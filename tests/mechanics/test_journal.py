"""Plain journal bearings (short-bearing theory) against a published table and against the
short-bearing Reynolds equation integrated numerically.

* Friswell et al. (2010), Example 5.5.1: D = 100 mm, L = 30 mm, c = 0.1 mm, eta = 0.1 Pa s,
  W = 525 N at 1500 rpm; their K and C to the digits printed.
* The film force ``-int p (cos t, sin t) R dt`` with the short-bearing pressure (parabolic
  across the length, cavitated where negative) integrated on a fine grid: the static
  equilibrium found by a root finder and the coefficients by central differences of the
  force in position and velocity; for several loads, load directions and both senses of
  rotation (the transforms of :func:`journal_bearing_table`).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import fsolve

from rheolin.errors import ModelError
from rheolin.io import parse_model
from rheolin.mechanics.journal import journal_bearing_table, short_journal_bearing

D, L, C_R, ETA = 0.1, 0.03, 1e-4, 0.1


def test_friswell_example_5_5_1() -> None:
    K, C, _ = short_journal_bearing(D, L, C_R, ETA, 525.0, 1500 * np.pi / 30)
    np.testing.assert_allclose(K / 1e6, [[12.81, 16.39], [-25.06, 8.815]], rtol=6e-4)
    np.testing.assert_allclose(C / 1e3, [[232.9, -81.92], [-81.92, 294.9]], rtol=3e-4)


def _reynolds(load: float, W: float, direction: np.ndarray, sense: int):  # type: ignore[no-untyped-def]
    """K, C (2 x 2, global x, y) of the short-bearing film by numerical integration."""
    R = D / 2
    t = np.linspace(0.0, 2 * np.pi, 100001)[:-1]
    dt = t[1] - t[0]
    ct, st = np.cos(t), np.sin(t)
    Om = sense * W

    def force(x: float, y: float, vx: float, vy: float) -> np.ndarray:
        h = C_R - x * ct - y * st
        G = Om / 2 * (x * st - y * ct) - vx * ct - vy * st
        p = np.maximum(-ETA * L**3 * G / h**3, 0.0)
        return -np.array([np.sum(p * ct), np.sum(p * st)]) * R * dt

    want = -load * direction  # the film holds the journal against the load

    def residual(z: np.ndarray) -> np.ndarray:
        return (force(z[0] * C_R, z[1] * C_R, 0, 0) - want) / load

    best = None
    for r in (0.3, 0.6, 0.85):  # starting points around the clearance circle
        for a in np.linspace(0.0, 2 * np.pi, 8, endpoint=False):
            z, *_ = fsolve(residual, [r * np.cos(a), r * np.sin(a)], xtol=1e-14,
                                    full_output=True)  # fmt: skip
            err = float(np.abs(residual(z)).max())
            if np.hypot(*z) < 1 and (best is None or err < best[0]):
                best = (err, z)
    assert best is not None and best[0] < 1e-10
    x0, y0 = best[1] * C_R
    K, C = np.zeros((2, 2)), np.zeros((2, 2))
    d, v = 1e-5 * C_R, 1e-5 * C_R * W
    for j in range(2):
        e = np.eye(2)[j]
        K[:, j] = -(
            force(x0 + d * e[0], y0 + d * e[1], 0, 0) - force(x0 - d * e[0], y0 - d * e[1], 0, 0)
        ) / (2 * d)
        C[:, j] = -(force(x0, y0, v * e[0], v * e[1]) - force(x0, y0, -v * e[0], -v * e[1])) / (
            2 * v
        )
    return K, C


@pytest.mark.parametrize(
    "load, angle, sense",
    [(100.0, -90.0, 1), (2000.0, -90.0, 1), (8000.0, -60.0, 1), (2000.0, 30.0, -1)],
)  # eccentricity ratios 0.03, 0.40, 0.66 and 0.40
def test_coefficients_against_the_integrated_reynolds_equation(load, angle, sense) -> None:
    W = 3000 * np.pi / 30
    direction = np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle))])
    Ks, Cs = journal_bearing_table(D, L, C_R, ETA, load, [W],
                                   load_direction=[*direction, 0.0], rotation=sense)  # fmt: skip
    K_ref, C_ref = _reynolds(load, W, direction, sense)
    scale_k, scale_c = np.abs(K_ref).max(), np.abs(C_ref).max()
    # the reference: trapezoidal sums over 1e5 points with the cavitation boundary's kink
    # moving inside a cell under the difference steps: about 1e-6 of the coefficients
    assert np.abs(Ks[0][:2, :2] - K_ref).max() < 2e-5 * scale_k
    assert np.abs(Cs[0][:2, :2] - C_ref).max() < 2e-5 * scale_c
    assert np.abs(Ks[0][2]).max() == 0 and np.abs(Ks[0][:, 2]).max() == 0  # axial: none


def test_journal_bearing_in_the_model_file() -> None:
    text = """
[model]
input_body = "r"
[[shafts]]
name = "r"
positions = "0 200 400 mm"
outer_diameter = "100 mm"
material = "steel"
[[shafts.bearings]]
name = "j"
node = 0
speeds = ["1000 rpm", "1500 rpm", "2000 rpm"]
[shafts.bearings.journal]
diameter = "100 mm"
length = "30 mm"
clearance = "0.1 mm"
viscosity = "0.1 Pa*s"
load = "525 N"
"""
    model = parse_model(text).model
    K, Dm, _ = model.bearing_coefficients("j", 1500 * np.pi / 30)
    K2, C2, _ = short_journal_bearing(D, L, C_R, ETA, 525.0, 1500 * np.pi / 30)
    np.testing.assert_allclose(K[:2, :2], K2, rtol=1e-12)
    np.testing.assert_allclose(Dm[:2, :2], C2, rtol=1e-12)
    with pytest.raises(ModelError, match="needs `speeds`"):
        parse_model(text.replace('speeds = ["1000 rpm", "1500 rpm", "2000 rpm"]\n', ""))
    with pytest.raises(ModelError, match=r"journal\.viscosity"):
        parse_model(text.replace('"0.1 Pa*s"', '"0.1 Pa"'))
    with pytest.raises(ModelError, match="cannot carry"):
        parse_model(text.replace('"525 N"', '"5e7 N"'))
