"""``rheolin critical-map`` in a subprocess: the critical speed it prints for the model's own
bearings is the Campbell diagram's forward 1x crossing (a different computation: modes over a
speed grid), the map reopens, and a bad stiffness range exits 2 naming the option."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from rheolin.io import parse_model
from rheolin.results.units import missing_units
from rheolin.stability import campbell

sys.path.insert(0, str(Path(__file__).parent))
from test_frf_cli import cli
from test_modes_cli import ROTOR


def test_critical_map_matches_the_campbell_crossing(tmp_path: Path) -> None:
    (tmp_path / "rotor.toml").write_text(ROTOR)
    res = cli("critical-map", str(tmp_path / "rotor.toml"), "--stiffness", "1e6:1e9:7 N/m",
              "--out", str(tmp_path / "out"))  # fmt: skip
    assert res.returncode == 0, res.stderr
    first = float(re.findall(r"│\s*1\s*│\s*([0-9.]+)\s*│", res.stdout)[0])
    model = parse_model(ROTOR).model
    W = np.linspace(0.9, 1.1, 201) * first * np.pi / 30
    crossings = [
        c.speed * 30 / np.pi
        for c in campbell(model, W).critical_speeds
        if c.order == "1x rotor" and c.whirl == "forward"
    ]
    assert crossings and first == pytest.approx(crossings[0], rel=1e-4)
    ds = xr.open_dataset(tmp_path / "out" / "critical_map.nc")
    assert missing_units(ds) == []
    assert ds["critical_speed"].shape == (7, 4)
    assert list(ds["bearing"].values) == ["left", "right"]
    speeds = ds["critical_speed"].values[:, 0]
    assert np.all(np.diff(speeds) > 0)  # stiffer bearings, higher first critical speed


def test_critical_map_bad_range_exits_2(tmp_path: Path) -> None:
    (tmp_path / "rotor.toml").write_text(ROTOR)
    res = cli("critical-map", str(tmp_path / "rotor.toml"), "--stiffness", "1e9:1e6:5")
    assert res.returncode == 2 and "--stiffness" in res.stderr
    res = cli("critical-map", str(tmp_path / "rotor.toml"), "--stiffness", "1e6:1e9:5 kg")
    assert res.returncode == 2 and "--stiffness" in res.stderr
    res = cli("critical-map", str(tmp_path / "rotor.toml"), "--bearing", "nope")
    assert res.returncode == 2 and "no bearing 'nope'" in res.stderr
