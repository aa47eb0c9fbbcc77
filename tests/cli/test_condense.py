"""``rheolin condense``: a scikit-fem solid exported as Matrix Market and as Abaqus matrix
input, condensed from a spec file; the body's elastic modes against the full FE model's
(eigsh shift-invert), its printed snippet taken by a model file; bad specs exit 2 naming the
field."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io as sio
import scipy.linalg as sla

pytest.importorskip("skfem")
from rheolin.fe.solid import solid_model, tensor_block
from run_cli import cli

L = 0.3
SPEC = """
[fe]
format = "matrix-market"
stiffness = "K.mtx"
mass = "M.mtx"
nodes = "nodes.csv"

[condense]
modes = 40

[[interface]]
name = "left"
reference = ["0 mm", "25 mm", "20 mm"]
box = ["-1 mm", "-1 m", "-1 m", "1 mm", "1 m", "1 m"]

[[interface]]
name = "right"
reference = ["300 mm", "25 mm", "20 mm"]
kind = "average"
sphere = { centre = ["300 mm", "25 mm", "20 mm"], radius = "40 mm" }
"""


@pytest.fixture(scope="module")
def exported(tmp_path_factory):  # type: ignore[no-untyped-def]
    d = tmp_path_factory.mktemp("fe")
    fe = solid_model(*tensor_block((L, 0.05, 0.04), (12, 2, 2)))
    sio.mmwrite(d / "K.mtx", fe.K)
    sio.mmwrite(d / "M.mtx", fe.M)
    np.savetxt(d / "nodes.csv", fe.coordinates, delimiter=",")
    (d / "spec.toml").write_text(SPEC)
    return fe, d


def test_condense_matches_the_full_model_and_feeds_a_model_file(exported):  # type: ignore[no-untyped-def]
    fe, d = exported
    res = cli("condense", str(d / "spec.toml"), "--out", str(d / "housing.npz"))
    assert res.returncode == 0, res.stderr
    assert "condensed 351 FE DOFs to 52" in res.stdout  # 2 interfaces x 6 + 40 modes
    with np.load(d / "housing.npz") as z:
        K, M = z["K"], z["M"]
    full = sla.eigh(fe.K.toarray(), fe.M.toarray(), eigvals_only=True)[6:9]  # dense: exact
    red = np.sort(np.abs(np.linalg.eigvals(np.linalg.solve(M, K))))[6:9]
    assert np.allclose(np.sqrt(red), np.sqrt(full), rtol=1e-3), (red, full)
    snippet = res.stdout[res.stdout.index("[[condensed_bodies]]") :]
    model = (
        '[model]\nname = "rotor in a housing"\ninput_body = "rotor"\nspeed = "1000 rpm"\n\n'
        '[[rigid_bodies]]\nname = "rotor"\nposition = "0.3 0.025 0.02 m"\nmass = "5 kg"\n'
        'inertia = ["0.01 kg*m^2", "0.01 kg*m^2", "0.02 kg*m^2"]\n\n'
        '[[rigid_bodies.bearings]]\nname = "bearing"\nnode = 0\nother_body = "housing"\n'
        'other_node = 1\nstiffness = ["1e8 N/m", "1e8 N/m"]\n\n'
        + snippet
        + '\n[[condensed_bodies.bearings]]\nname = "foot"\nnode = 0\ncomponents = "all"\n'
        'stiffness = ["1e8 N/m", "1e8 N/m", "1e8 N/m", "1e6 N*m/rad", "1e6 N*m/rad", '
        '"1e6 N*m/rad"]\n'
    )
    (d / "model.toml").write_text(model)
    check = cli("validate", "model.toml", cwd=d)
    assert check.returncode == 0, check.stdout + check.stderr


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (("modes = 40", "modes = -1"), "condense.modes"),
        (('kind = "average"', 'kind = "glued"'), r"interface\[1\].kind"),
        (('centre = ["300 mm"', 'centre = ["3000 mm"'), r"interface\[1\]: selects no FE node"),
        (('radius = "40 mm"', 'radius = "0.1 mm"'), r"interface\[1\] \('right'\)\.nodes: the set"),
        (('stiffness = "K.mtx"', 'stiffness = "nope.mtx"'), "fe.stiffness: no such file"),
        (("modes = 40", "modes = 40\nwobble = 1"), "condense.wobble: unknown field"),
    ],
)
def test_bad_spec_exits_2_naming_the_field(exported, tmp_path, edit, field):  # type: ignore[no-untyped-def]
    _, d = exported
    spec = d / f"bad_{abs(hash(field))}.toml"
    spec.write_text(SPEC.replace(*edit))
    res = cli("condense", str(spec), "--out", str(tmp_path / "b.npz"))
    assert res.returncode == 2, res.stdout + res.stderr
    import re

    assert re.search(field, res.stderr), res.stderr
    assert "Traceback" not in res.stderr
    assert not (tmp_path / "b.npz").exists()
