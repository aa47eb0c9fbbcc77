"""The ``[[planetary]]`` table: the wind-turbine example round-trips through ``Model.to_toml``
to identical matrices, and broken sets are refused naming the field (exit 2 in the CLI)."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from rheolin.data import example_path, example_text
from rheolin.errors import ModelError
from rheolin.io import load_model, parse_model

RPM = np.pi / 30


def _same_system(a, b) -> None:
    for name in "MDK":
        A, B = getattr(a.system, name), getattr(b.system, name)
        assert set(A) == set(B), name
        for k in A:
            assert abs(A[k] - B[k]).max() <= 1e-12 * max(abs(A[k]).max(), 1e-300), (name, k)
    assert set(a.system.f) == set(b.system.f)
    for k in a.system.f:
        assert np.allclose(a.system.f[k], b.system.f[k], rtol=1e-12, atol=0)


def test_wind_turbine_round_trips_identically():
    m = load_model(example_path("wind-turbine"))
    again = parse_model(m.to_toml()).model
    for rpm in (10.0, 22.1):
        _same_system(m.assemble(rpm * RPM), again.assemble(rpm * RPM))


def _edit(old: str, new: str) -> str:
    text = example_text("wind-turbine")
    assert old in text, old
    return text.replace(old, new, 1)


@pytest.mark.parametrize(
    ("old", "new", "pattern"),
    [
        ("ring_teeth = 99", "ring_teeth = 98", r"planetary\[0\]: `ring_teeth`: 98 teeth: a ring "),
        ("ring_teeth = 99", "ring_teeth = 100", r"planetary\[0\]: `ring_teeth`: 3 equally spaced"),
        ("planets = 3", 'planet_angles = ["0 deg", "60 deg", "180 deg"]',
         r"planetary\[0\]: `planet_angles`: planets 0 and 1 \(60 deg apart\) collide"),
        ("planets = 3", "planets = 3\nplanet_angles = [0.0, 2.0, 4.0]",
         r"planetary\[0\]: give `planets` .* or `planet_angles`"),
        ('sun_body = "sun"', 'sun_body = "sunn"', r"planetary\[0\]: `sun_body`: no body named"),
        ("[planetary.sun_mesh]\n", "[planetary.sun_mesh]\nstifness = 1\n",
         r"planetary\[0\]\.sun_mesh\.stifness"),
        ("speed_ratio = 0\n", "", r"planetary: the input speed does not determine the speeds"),
        ('inner_diameter = "250 mm"\nmaterial = "steel"',
         'inner_diameter = "250 mm"', r"planet: `density` is required"),
    ],
    ids=["ring too small", "does not assemble", "planets collide", "planets and angles",
         "no such body", "unknown key", "nothing held", "planet material"],
)  # fmt: skip
def test_broken_sets_are_refused_naming_the_field(old, new, pattern):
    with pytest.raises(ModelError, match=pattern):
        parse_model(_edit(old, new))


def test_cli_validate_refuses_a_broken_set_with_exit_2(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(_edit("ring_teeth = 99", "ring_teeth = 100"))
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "COLUMNS": "200"}
    run = subprocess.run([sys.executable, "-m", "rheolin.cli", "validate", str(path)],
                         capture_output=True, text=True, env=env, timeout=300)  # fmt: skip
    assert run.returncode == 2, run.stdout + run.stderr
    assert "planetary[0]" in run.stdout + run.stderr and "Traceback" not in run.stderr
