"""``rheolin run`` on a preloaded model (torques, rolling bearings, a load-dependent mesh):
the operating point in summary.json against closed forms; bad entries exit 2 naming the
field."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from rheolin.data import example_text
from run_cli import cli

PAIR = example_text("preloaded")


def test_run_reports_the_operating_point(tmp_path: Path) -> None:
    (tmp_path / "pair.toml").write_text(PAIR)
    res = cli("run", str(tmp_path / "pair.toml"), "--out", str(tmp_path / "out"), "--json",
              "--stability", "off", "--no-plots")  # fmt: skip
    assert res.returncode == 0, res.stderr
    op = json.loads((tmp_path / "out" / "summary.json").read_text())["operating_point"]
    T, z1, z2, mod, alpha, k0, b = 60.0, 21, 52, 4e-3, np.radians(20.0), 4e8, 0.02
    F = T / (mod * z1 / 2 * np.cos(alpha))  # mesh force from the input torque
    mesh = op["meshes"]["m1"]
    assert mesh["force_N"] == pytest.approx(F, rel=1e-9)
    k = k0 * (F / (b * 1e5)) ** 0.25  # ISO 6336 below 100 N/mm
    assert mesh["deflection_m"] == pytest.approx(F / k, rel=1e-9)
    assert mesh["stiffness_N_per_m"] == pytest.approx(4 / 3 * k, rel=1e-9)
    assert op["torques_N_m"]["output"] == pytest.approx(T * z2 / z1, rel=1e-9)
    # the pinion's two bearings share the mesh force and the pinion's weight (lever rule:
    # the gear at mid-span); the mesh force acts along the line of action
    pA, pB = op["bearings"]["pA"], op["bearings"]["pB"]
    assert pA["load_N"] == pytest.approx(pB["load_N"], rel=1e-6)
    assert 0 < pA["in_contact"] < 9


@pytest.mark.parametrize(
    ("old", "new", "field", "key"),
    [
        ('stiffness = "8e9 N/m^1.5"\n', "", "shafts[0].rolling_bearings[0]", "stiffness"),
        ('stiffness = "8e9 N/m^1.5"', 'stiffness = "8e9 N/m"', "rolling_bearings[0]", "N/m^1.5"),
        ("elements = 9", "elements = 2", "shafts[0].rolling_bearings[0]", "elements"),
        ('torque = "60 N*m"', 'torque = "60 N"', "torques[0].torque", "N*m"),
        ('face_width = "20 mm"\n', "", "meshes[0]", "face_width"),
        ('torque = "reaction"', 'torque = "lots"', "torques[1].torque", "N*m"),
    ],
)
def test_bad_preload_entries_exit_2_naming_the_field(tmp_path, old, new, field, key) -> None:
    assert old in PAIR
    (tmp_path / "bad.toml").write_text(PAIR.replace(old, new))
    res = cli("run", str(tmp_path / "bad.toml"), "--out", str(tmp_path / "o"))
    assert res.returncode == 2, res.stderr
    assert field in res.stderr and key in res.stderr, res.stderr
    assert "Traceback" not in res.stderr
    assert not (tmp_path / "o").exists()


def test_preloaded_model_file_round_trip(tmp_path: Path) -> None:
    """``Model.to_toml`` writes the rolling bearings, torques and mesh load law: the file
    reloads to the same operating point (static displacement to round-off)."""
    from rheolin.io import load_model

    (tmp_path / "pair.toml").write_text(PAIR)
    m = load_model(tmp_path / "pair.toml")
    m.to_toml(tmp_path / "again.toml")
    again = load_model(tmp_path / "again.toml")
    w = 100.0
    a, b = m.operating_point(w), again.operating_point(w)
    assert np.abs(a.displacement - b.displacement).max() <= 1e-12 * np.abs(a.displacement).max()
    assert a.torques == pytest.approx(b.torques, rel=1e-12)


def test_a_study_varies_the_torque_and_a_rolling_bearing() -> None:
    """``--vary`` paths into the preload tables: the torque by its name, a rolling bearing by
    ``bearings.NAME``; each grid point's operating point carries the value (mesh force
    ``T / r_b1``)."""
    import tomllib

    from rheolin.io import parse_document
    from rheolin.study.params import apply, parse_vary

    doc = tomllib.loads(PAIR)
    torque = parse_vary("torques.input.torque=20:60:3 N*m", doc)
    clearance = parse_vary("bearings.pA.clearance=0:10:2 um", doc)
    assert torque.field == "torques[0].torque"
    assert clearance.field == "shafts[0].rolling_bearings[0].clearance"
    rb1 = 4e-3 * 21 / 2 * np.cos(np.radians(20.0))
    for i, T in enumerate((20.0, 40.0, 60.0)):
        model = parse_document(apply(doc, [(torque, i), (clearance, 1)])).model
        assert model.rolling["pA"]["law"].clearance == pytest.approx(10e-6)
        op = model.operating_point(100.0)
        assert op.meshes["m1"].force == pytest.approx(T / rb1, rel=1e-9)


def test_linearized_model_file_keeps_the_preloads(tmp_path: Path) -> None:
    """The linearized model (linear joints with ``preload``) written as a model file and
    reloaded: the same static response and the same bearing forces."""
    import rheolin as rl
    from rheolin.io import load_model
    from rheolin.results.outputs import bearing_force_array

    (tmp_path / "pair.toml").write_text(PAIR)
    lin = load_model(tmp_path / "pair.toml").operating_point(100.0).model
    lin.to_toml(tmp_path / "lin.toml")
    again = load_model(tmp_path / "lin.toml")
    assert not again.preloaded and again.joints["pA"]["preload"] is not None
    out = []
    for m in (lin, again):
        a = m.assemble(100.0)
        sol = rl.solve(a.system, [0])
        out.append((np.real(sol.q[0]), np.real(bearing_force_array(sol, a, "pA")[1][0])))
    assert np.abs(out[0][0] - out[1][0]).max() <= 1e-12 * np.abs(out[0][0]).max()
    assert np.abs(out[0][1] - out[1][1]).max() <= 1e-9 * np.abs(out[0][1]).max()


def test_validate_finds_the_static_equilibrium_or_names_the_joint(tmp_path: Path) -> None:
    """``rheolin validate`` on a preloaded file solves its static equilibrium: found for the
    example; a pinion bearing whose table saturates below its load exits 2 naming it."""
    (tmp_path / "ok.toml").write_text(PAIR)
    res = cli("validate", str(tmp_path / "ok.toml"))
    assert res.returncode == 0 and "static equilibrium found" in res.stdout, res.stderr
    old = 'name = "pB"\nnode = 2\nlaw = "radial"\nkind = "roller"\nstiffness = "1.5e9 N/m^(10/9)"'
    new = ('name = "pB"\nnode = 2\nlaw = "table"\ndeflection = "0 10 20 30 um"\n'
           'force = "0 40 50 50 N"')  # fmt: skip
    assert old in PAIR
    (tmp_path / "weak.toml").write_text(PAIR.replace(old, new))
    res = cli("validate", str(tmp_path / "weak.toml"))
    assert res.returncode == 2 and "'pB'" in res.stderr and "Traceback" not in res.stderr
