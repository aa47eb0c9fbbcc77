"""The files' unit convention (rheolin.results.units) and the complex amplitude helper: the
unbalance response of a rigid rotor on isotropic springs read back with
complex_amplitude equals the closed form U W^2 / (k - m W^2 + i c W)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import rheolin as rl
from rheolin.results import complex_amplitude, point_dataset, solve_point, write_dataset
from rheolin.results.units import UNITS, missing_units, significant, with_units

M, K, C, U = 2.0, 1e6, 80.0, 1e-4


def rigid_rotor() -> rl.Model:
    m = rl.Model()
    m.add_rigid_body("r", (0.0, 0.0, 0.0), M, (0.01, 0.01, 0.02))
    m.add_disk("r", 0, unbalance=U)
    m.add_bearing("b", "r", 0, stiffness=[K, K, K, 1e4, 1e4, 1e4], damping=[C, C, C, 1, 1, 1],
                  components=None)  # fmt: skip
    return m


@pytest.mark.parametrize("W", [300.0, 707.0, 1500.0])  # below, at and above sqrt(k / m)
def test_complex_amplitude_is_the_closed_form_unbalance_response(W, tmp_path):
    ds = point_dataset(solve_point(rigid_rotor(), W, stability=False))
    path = write_dataset(ds, tmp_path / "results.nc")
    with xr.open_dataset(path) as back:
        a = complex_amplitude(back)["displacement"].sel(node="r:0", harmonic=1)
        assert missing_units(back) == []
    ref = U * W**2 / (K - M * W**2 + 1j * C * W)
    assert abs(complex(a.sel(component="ux"))) == pytest.approx(abs(ref), rel=1e-9)
    assert abs(complex(a.sel(component="uy"))) == pytest.approx(abs(ref), rel=1e-9)
    # a circular forward orbit: uy lags ux by a quarter turn
    ratio = complex(a.sel(component="uy")) / complex(a.sel(component="ux"))
    assert ratio == pytest.approx(-1j, abs=1e-9)
    assert a.attrs["units"].startswith("m")


def test_significant_removes_the_round_trip_noise_of_rpm():
    rpm = [float(x) * np.pi / 30 * 30 / np.pi for x in range(500, 6001, 50)]
    assert [significant(x) for x in rpm] == [float(x) for x in range(500, 6001, 50)]
    assert significant(1234.56789012345678) == 1234.56789012


def test_with_units_fills_only_what_is_missing():
    ds = xr.Dataset(
        {"frequency": ("n", [1.0]), "stable": ("n", [1]), "custom": ("n", [2.0])},
        coords={"n": [0]},
    )
    ds["frequency"].attrs["units"] = "rad/s"  # a writer's own unit is kept
    out = with_units(ds)
    assert out["frequency"].attrs["units"] == "rad/s" and out["stable"].attrs["units"] == "1"
    assert missing_units(out) == ["custom", "n"]
    assert UNITS["max_real"] == "1/s" and UNITS["speed"] == "rad/s"
