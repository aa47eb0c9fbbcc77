"""The gearbox-in-a-housing example: built on the fly, read as a model file; an almost rigid
housing (E x 1e4) gives the bearing forces of the gearbox on rigid supports (the embedded
example file, an independent model), while the steel one changes them (it is in the load
path)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("skfem")

from rheolin.data import example_path
from rheolin.fe.gearbox_housing import BEARINGS, build
from rheolin.io import load_model
from rheolin.results.compute import solve_point
from rheolin.results.outputs import bearing_force_array

W = 3000 * np.pi / 30


def _forces(model):  # type: ignore[no-untyped-def]
    p = solve_point(model, W, order=1, stability=False)
    assert p.solution.success, p.solution.message
    out = {}
    for name, *_ in BEARINGS:
        m, F = bearing_force_array(p.solution, p.assembled, name)
        out[name] = dict(zip(m.tolist(), F[:, :3], strict=True))
    return out


def _worst(a, b):  # type: ignore[no-untyped-def]
    """Largest difference of the bearing force vectors over bearings and harmonics, relative
    to each bearing's largest force."""
    worst = 0.0
    for name in a:
        scale = max(np.abs(v).max() for v in b[name].values())
        for m, v in b[name].items():
            worst = max(worst, float(np.abs(a[name][m] - v).max() / scale))
    return worst


def test_rigid_housing_limit_and_steel_housing(tmp_path):  # type: ignore[no-untyped-def]
    rigid = _forces(load_model(example_path("gearbox")))
    stiff = build(tmp_path / "stiff", 0.015, elastic_modulus=2.1e15)
    steel = build(tmp_path / "steel", 0.015)
    assert (tmp_path / "steel" / "housing.npz").is_file()
    assert _worst(_forces(load_model(stiff)), rigid) < 1e-3
    assert _worst(_forces(load_model(steel)), rigid) > 1e-2


def test_cli_example_needs_a_directory_and_writes_both_files(tmp_path):  # type: ignore[no-untyped-def]
    from typer.testing import CliRunner

    from rheolin.cli import app

    runner = CliRunner()
    res = runner.invoke(app, ["example", "gearbox-housing"])
    assert res.exit_code == 2 and "--out" in res.output
    res = runner.invoke(app, ["example", "rotor", "--out", str(tmp_path / "r")])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "r" / "rotor.toml").read_text() == example_path("rotor").read_text()
