"""Model.to_toml: the round trip model -> TOML -> model gives identical matrices."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rheolin.data import example_path
from rheolin.errors import ModelError
from rheolin.io.loader import load_model, parse_model
from rheolin.io.ross import model_from_ross
from rheolin.mechanics.model import Model

sys.path.insert(0, str(Path(__file__).parent))
from test_ross import ROSS_TEXT


def _identical(a, b, speeds=(120.0, 650.0)):
    for W in speeds:
        x, y = a.assemble(W).system, b.assemble(W).system
        for X in "MDK":
            p, q = getattr(x, X), getattr(y, X)
            assert set(p) == set(q)
            for k in p:
                assert (p[k] != q[k]).nnz == 0, (W, X, k)
        assert set(x.f) == set(y.f) and all(np.array_equal(x.f[k], y.f[k]) for k in x.f)


def _tables_model():
    m = Model(input_body="s")
    m.add_shaft("s", [0.0, 0.2, 0.5, 0.7], outer_diameter=[0.05, 0.06, 0.05],
                inner_diameter=0.01, outer_diameter_right=[0.05, 0.05, 0.05],
                elastic_modulus=[2.1e11, 2.0e11, 2.1e11], poisson_ratio=[0.3, 0.29, 0.3],
                material_damping=1e-5, material="steel")  # fmt: skip
    m.add_shaft_layer("s", [1, 2], 0.09, 0.06, elastic_modulus=1e3, shear_modulus=400.0,
                      density=2700.0)  # fmt: skip
    m.add_disk("s", 1, outer_diameter=0.3, width=0.04, material="steel")
    m.add_disk("s", 1, unbalance=2e-4, unbalance_angle=0.3, couple_unbalance=1e-5)
    m.add_bearing("a", "s", 0, [[[1e7, 2e6], [-1e6, 1.1e7]]] * 2 + [[[2e7, 3e6], [-2e6, 2e7]]],
                  [100.0, 120.0, 150.0], speeds=[50.0, 300.0, 900.0], mass=0.1,
                  interpolation="pchip")  # fmt: skip
    m.add_bearing("b", "s", 3, [1e7, 1e7, 1e8, 1e3], 10.0, components=["ux", "uy", "uz", "phiz"])
    m.add_rigid_body("housing", (0.0, 0.0, 0.0), 20.0, (1.0, 1.0, 2.0), speed_ratio=0)
    m.add_bearing("c", "housing", 0, 1e9, 0.0, components=None)
    m.add_force("f", "s", 2, force=(10.0, 0.0, 0.0), order=2, phase=0.1)
    m.set_gravity()
    return m


def test_examples_round_trip_identically():
    for name in ("gearbox", "rotor"):
        m = load_model(example_path(name))
        _identical(m, parse_model(m.to_toml()).model)


def test_tables_layers_taper_and_materials_round_trip_identically(tmp_path):
    m = _tables_model()
    path = tmp_path / "m.toml"
    text = m.to_toml(path)
    assert path.read_text() == text
    _identical(m, load_model(path))


def test_ross_import_round_trips_identically():
    import tomllib

    m = model_from_ross(tomllib.loads(ROSS_TEXT))
    _identical(m, parse_model(m.to_toml()).model, speeds=(80.0, 250.0, 700.0))


def test_matrices_only_condensed_body_is_refused():
    m = Model()
    m.add_condensed_body("h", [[0, 0, 0]], M=np.eye(6), K=np.eye(6))
    with pytest.raises(ModelError, match="condensed body 'h'"):
        m.to_toml()


def test_cli_import_ross(tmp_path):
    src = tmp_path / "rotor.toml"
    src.write_text(ROSS_TEXT)
    run = subprocess.run([sys.executable, "-m", "rheolin.cli", "import-ross", str(src)],
                         capture_output=True, text=True)  # fmt: skip
    assert run.returncode == 0, run.stderr
    _identical(model_from_ross(src), parse_model(run.stdout).model)
    bad = subprocess.run([sys.executable, "-m", "rheolin.cli", "import-ross",
                          str(tmp_path / "none.toml")], capture_output=True, text=True)  # fmt: skip
    assert bad.returncode == 2 and "cannot read ROSS file" in bad.stderr
    assert len(bad.stderr.strip().splitlines()) == 1
