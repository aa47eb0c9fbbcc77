"""Bad or impossible input is refused naming its field (exit 2), never an internal error (exit
3) or a silent change: environment variables, deeply nested files, pickled arrays, ROSS files
with unit strings, condense specs, impossible physics (inertias, mesh stiffness), sets that
list an entry twice, and sums whose entries add."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

import rheolin as rl
from rheolin.data import example_text
from rheolin.errors import ModelError
from rheolin.io import parse_model


def _refused(res, *needles: str) -> str:
    """The one ``error:`` line of a command that exited 2; it names ``needles``."""
    assert res.exit_code == 2, (res.exit_code, res.stdout, res.stderr)
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert lines and lines[0].startswith("error: "), res.stderr
    assert "Traceback" not in res.stderr + res.stdout and "internal error" not in res.stderr
    for n in needles:
        assert n in res.stderr, (n, res.stderr)
    return lines[0]


@pytest.mark.parametrize(
    "name, value, needle",
    [
        ("RHEOLIN_MEMORY_BUDGET", "banana", "cannot read a memory size"),
        ("RHEOLIN_SOLVE_MEMORY", "-5GB", "positive"),
        ("RHEOLIN_SOLVE_MEMORY", "1e400 GB", "positive and finite"),
    ],
)
def test_unreadable_budget_variables_are_refused_naming_them(
    invoke, rotor, tmp_path, monkeypatch, name, value, needle
):
    monkeypatch.setenv(name, value)
    _refused(invoke("validate", rotor), name, needle)
    _refused(invoke("run", rotor, "--out", tmp_path / "o"), name)
    assert not (tmp_path / "o").exists()


def test_deeply_nested_files_are_refused(invoke, tmp_path):
    deep = tmp_path / "deep.toml"
    deep.write_text("a = " + "[" * 5000 + "]" * 5000 + "\n")
    _refused(invoke("validate", deep), "deep.toml", "nested too deeply")
    spec = tmp_path / "spec.toml"
    spec.write_text("fe = " + "[" * 5000 + "]" * 5000 + "\n")
    _refused(invoke("condense", spec, "--out", tmp_path / "b.npz"), "nested too deeply")


def _condensed_file(tmp_path, arrays: dict) -> str:
    np.savez(tmp_path / "body.npz", **arrays)
    return (
        '[model]\nspeed = "100 rpm"\n[[condensed_bodies]]\nname = "h"\npath = "body.npz"\n'
        'speed_ratio = 0\n[[forces]]\nname = "f"\nbody = "h"\nnode = 0\nforce = [1, 0, 0]\n'
        'order = 1\nreference_body = "h"\n'
    )


@pytest.mark.parametrize(
    "arrays, needle",
    [
        ({"frame": np.array([{"code": 1}], dtype=object)}, "pickled"),
        ({"M": np.array(["a"] * 36).reshape(6, 6)}, "not numeric"),
        ({"K": np.full((6, 6), np.nan)}, "NaN"),
    ],
)
def test_npz_with_objects_strings_or_nan_is_refused(invoke, tmp_path, arrays, needle):
    base = {"M": np.eye(6), "K": np.eye(6), "positions": np.zeros((1, 3))}
    (tmp_path / "m.toml").write_text(_condensed_file(tmp_path, {**base, **arrays}))
    _refused(invoke("validate", tmp_path / "m.toml"), "condensed_bodies[0].path", needle)


def test_ross_file_with_a_unit_string_is_refused_naming_the_element(invoke, tmp_path):
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parents[1] / "io"))
    from test_ross import ROSS_TEXT

    bad = ROSS_TEXT.replace("E = 211000000000.0", 'E = "211 GPa"', 1)
    (tmp_path / "r.toml").write_text(bad)
    _refused(invoke("import-ross", tmp_path / "r.toml"), "ShaftElement_0.material.E", "211 GPa")
    (tmp_path / "r.toml").write_text(ROSS_TEXT.replace("Id = 0.1", "Id = [0.1]"))
    _refused(invoke("import-ross", tmp_path / "r.toml"), "DiskElement_Disk 0.Id")
    (tmp_path / "r.toml").write_text('ShaftElement_9 = "x"\n' + ROSS_TEXT)  # not a table
    _refused(invoke("import-ross", tmp_path / "r.toml"), "ShaftElement_9: expected a table")
    (tmp_path / "r.toml").write_text(ROSS_TEXT)
    _refused(invoke("import-ross", tmp_path / "r.toml", "--out", tmp_path), "--out")


@pytest.mark.parametrize(
    "inertia",
    [[0.01, 0.01, 0.05], [[0.02, 0.0, 0.0], [0.0, 0.001, 0.0], [0.0, 0.0, 0.001]]],
)
def test_principal_inertias_that_no_body_has_are_refused(inertia):
    """``I_a + I_b - I_c = 2 int x_c^2 dm >= 0``: each principal moment is at most the sum of
    the other two (a thin disk, I_p = 2 I_d, is the limit and is accepted)."""
    m = rl.Model()
    with pytest.raises(ModelError, match=r"`inertia`: principal moments .* I3 <= I1 \+ I2"):
        m.add_rigid_body("r", (0, 0, 0), 2.0, inertia)
    m.add_rigid_body("thin", (0, 0, 0), 2.0, (0.01, 0.01, 0.02))  # the limit: accepted
    m.add_shaft("s", [0.0, 0.5], outer_diameter=0.05, material="steel")
    with pytest.raises(ModelError, match="principal moments"):
        m.add_disk("s", 0, mass=1.0, inertia=inertia)
    text = example_text("rotor").replace(
        'outer_diameter = "200 mm"\nwidth = "30 mm"\ndensity = "7850 kg/m^3"     # steel\n'
        'inner_diameter = "30 mm"\n',
        'mass = "7 kg"\ninertia = ["0.01 kg*m^2", "0.01 kg*m^2", "0.05 kg*m^2"]\n',
    )
    with pytest.raises(ModelError, match=r"shafts\[0\]\.disks\[0\]: `inertia`"):
        parse_model(text)


def test_a_single_tooth_pair_stiffer_than_two_is_refused():
    text = example_text("gearbox").replace(
        'single_stiffness = "2.8e8 N/m"', 'single_stiffness = "5.8e8 N/m"', 1
    )
    with pytest.raises(ModelError, match=r"meshes\[0\]: `single_stiffness` .* exceeds"):
        parse_model(text)


def test_a_layer_listing_an_element_twice_is_refused():
    text = example_text("rotor").replace(
        "[[shafts.disks]]",
        '[[shafts.layers]]\nelements = [0, 0]\nouter_diameter = "40 mm"\n'
        'inner_diameter = "30 mm"\npoisson_ratio = 0.3\n\n[[shafts.disks]]',
        1,
    )
    with pytest.raises(ModelError, match=r"shafts\[0\]\.layers\[0\]: `elements`: element 0"):
        parse_model(text)


def test_transmission_error_entries_at_one_harmonic_add():
    """``e(t) = sum amplitude cos(j W_m t + phase)``: 3 um at 0 deg and 2 um at 90 deg on
    harmonic 1 are the phasor ``(3 + 2i) / 2`` um; a constant offset adds too."""
    text = example_text("gearbox").replace(
        'transmission_error = [{ harmonic = 1, amplitude = "3 um" }]',
        'transmission_error = [{ harmonic = 1, amplitude = "3 um" }, '
        '{ harmonic = 1, amplitude = "2 um", phase = "90 deg" }, '
        '{ harmonic = 0, amplitude = "1 um" }, { harmonic = 0, amplitude = "4 um", '
        'phase = "180 deg" }]',
    )
    te = parse_model(text).model.meshes["stage1"]["transmission_error"]
    assert abs(te[1] - (3e-6 + 2e-6j) / 2) < 1e-18
    assert abs(te[0] - (1e-6 - 4e-6)) < 1e-18


def test_vary_of_a_value_and_a_part_of_it_is_refused(invoke, rotor, tmp_path):
    res = invoke(
        "sweep", rotor, "--speeds", "1000rpm", "--workers", "1", "--no-plots",
        "--vary", "bearings.drive_end.stiffness=1e7:5e7:2 N/m",
        "--vary", "bearings.drive_end.stiffness[0]=1e7:5e7:2 N/m", "--out", tmp_path / "s",
    )  # fmt: skip
    _refused(res, "--vary", "already varied")
    assert not (tmp_path / "s").exists()


def _fe_spec(tmp_path, **changes: str) -> None:
    pytest.importorskip("skfem")
    import scipy.io as sio

    from rheolin.fe.solid import solid_model, tensor_block

    fe = solid_model(*tensor_block((0.3, 0.05, 0.04), (6, 2, 2)))
    sio.mmwrite(tmp_path / "K.mtx", fe.K)
    sio.mmwrite(tmp_path / "M.mtx", -fe.M if changes.pop("negative_mass", "") else fe.M)
    np.savetxt(tmp_path / "nodes.csv", fe.coordinates, delimiter=",")
    spec = {
        "fe": {"format": "matrix-market", "stiffness": "K.mtx", "mass": "M.mtx",
               "nodes": "nodes.csv"},
        "condense": {"modes": 6},
        "interface": [
            {"name": "left", "reference": ["0 mm", "25 mm", "20 mm"],
             "box": ["-1 mm", "-1 m", "-1 m", "1 mm", "1 m", "1 m"]},
            {"name": "right", "reference": ["300 mm", "25 mm", "20 mm"],
             "box": ["299 mm", "-1 m", "-1 m", "301 mm", "1 m", "1 m"]},
        ],
    }  # fmt: skip
    if "cutoff" in changes:
        spec["condense"]["cutoff"] = changes["cutoff"]
    if "name" in changes:
        spec["interface"][1]["name"] = changes["name"]
    import tomli_w

    (tmp_path / "spec.toml").write_text(tomli_w.dumps(spec))
    assert tomllib.loads((tmp_path / "spec.toml").read_text())


@pytest.mark.parametrize(
    "change, needles",
    [
        ({"negative_mass": "yes"}, ("fe.mass", "negative diagonal")),
        ({"cutoff": "-2 kHz"}, ("condense.cutoff", "> 0")),
        ({"name": "left"}, ("interface[1].name", "'left'")),
    ],
)
def test_condense_specs_with_impossible_or_repeated_entries_are_refused(
    invoke, tmp_path, change, needles
):
    _fe_spec(tmp_path, **change)
    _refused(invoke("condense", tmp_path / "spec.toml", "--out", tmp_path / "b.npz"), *needles)
    assert not (tmp_path / "b.npz").exists()


def test_two_sided_joint_with_offsets_on_both_sides_assembles_to_the_lever_closed_form():
    """Found by H2: ``offset`` and ``other_offset`` together crashed the assembly (the levers
    were compared with ``== (None, None)``). Body ``a`` clamped, body ``b`` held only by the
    joint, both attached at z = 0.1 m (``b``'s node at z = 0.2): a force ``F`` along x on
    ``b`` deflects the attachment by ``F / k`` and tilts ``b`` by ``0.1 F / k_r``, so ``b``'s
    node moves ``F / k + 0.01 F / k_r``."""
    k, kr, F = 2e6, 3e4, 50.0
    m = rl.Model()
    m.add_rigid_body("a", (0, 0, 0), 1.0, (1, 1, 1))
    m.add_rigid_body("b", (0, 0, 0.2), 1.0, (1, 1, 1))
    m.add_bearing("clamp", "a", 0, stiffness=1e14, components=None)
    m.add_bearing("j", "a", 0, stiffness=[k, k, k, kr, kr, kr], components=None,
                  other_body="b", other_node=0, offset=(0, 0, 0.1),
                  other_offset=(0, 0, -0.1))  # fmt: skip
    m.add_force("f", "b", 0, force=(F, 0, 0))
    a = m.assemble(1.0)
    u = np.linalg.solve(a.system.K[0].toarray(), np.real(a.system.f[0]))
    ub = u[a.dofs("b", 0)]
    assert ub[0] == pytest.approx(F / k + 0.01 * F / kr, rel=1e-9)
    assert ub[4] == pytest.approx(0.1 * F / kr, rel=1e-9)


def test_two_torques_at_one_node_add():
    """Loads superpose (docs/model-format.md): 30 and 70 N m on the pinion of an external
    20:50 pair are balanced by the reaction ``(30 + 70) z2 / z1`` about the gear's own axis
    (power: ``T_p W_p + T_g W_g = 0`` with ``W_g = -W_p z1 / z2``)."""
    z1, z2, mod = 20, 50, 0.004
    m = rl.Model()
    m.add_rigid_body("p", (0, 0, 0), 1.0, (1e-3, 1e-3, 2e-3))
    m.add_rigid_body("g", (mod * (z1 + z2) / 2, 0, 0), 3.0, (0.01, 0.01, 0.02))
    for b in ("p", "g"):
        m.add_bearing(f"{b}b", b, 0, stiffness=1e9, components=["ux", "uy", "uz", "phix", "phiy"])
    m.add_gear_mesh("m", "p", 0, "g", 0, z1, z2, mod, stiffness=4e8)
    m.add_torque("a", "p", 0, 30.0)
    m.add_torque("b", "p", 0, 70.0)
    m.add_torque("out", "g", 0, "reaction")
    op = m.operating_point(1.0)
    assert op.torques["out"] == pytest.approx(100.0 * z2 / z1, rel=1e-10)
    assert op.notes() == []


def test_a_sweep_whose_every_point_fails_ends_honestly_with_its_files(invoke, rotor, tmp_path):
    """Every value leaves the free end without lateral support: each point fails (the
    message says why in sweep.json); the plots have nothing to draw. Exit 1, not 3."""
    import json

    res = invoke(
        "sweep", rotor, "--speeds", "1000,2000rpm", "--workers", "1", "--stability", "off",
        "--vary", "bearings.free_end.stiffness=0,1e-20 N/m", "--out", tmp_path / "s",
    )  # fmt: skip
    assert res.exit_code == 1, res.stderr
    assert "internal error" not in res.stderr
    table = json.loads((tmp_path / "s" / "sweep.json").read_text())
    assert not any(np.ravel(table["success"]))
    assert "no steady state" in json.dumps(table)


def test_report_of_result_files_rheolin_did_not_write_says_so_in_its_notes(invoke, tmp_path):
    """Tables of the wrong shape or types, nesting beyond the reader and netCDF files of
    another program under result names: the report is written, its first section and one
    warning line on stderr each name the file it could not use and why, and the exit code is
    1 (docs/cli.md; never 3); ``--out`` naming a directory is refused. The directory of a
    real run is reported with exit 0 and no warning."""
    import html
    import json
    import re
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from fuzz_surface import write_results

    write_results(tmp_path)
    expected = {
        "typed": ["left out: the result files (summary.json, sweep.json)"],
        "nested": ["sweep.json could not be read"],
        "foreign": ["sweep.json could not be read: a JSON NoneType", "left out"],
        "garbage": ["summary.json could not be read", "results.nc could not be read"],
    }
    for name, needles in expected.items():
        res = invoke("report", tmp_path / name)
        assert res.exit_code == 1 and "internal error" not in res.stderr, (name, res.stderr)
        page = (tmp_path / name / "report.html").read_text()
        notes = html.unescape(re.search(r'<section id="notes">(.*?)</section>', page, re.S)[1])
        warned = [ln for ln in res.stderr.splitlines() if ln.startswith("warning: report: ")]
        for needle in needles:
            assert needle in notes, (name, needle, notes)
            assert any(needle in line for line in warned), (name, needle, res.stderr)
    assert json.loads((tmp_path / "typed" / "summary.json").read_text())["warnings"] == 3
    _refused(invoke("report", tmp_path / "typed", "--out", tmp_path), "--out", "directory")


def test_a_rolling_bearing_with_a_billion_elements_is_refused_before_any_allocation(
    invoke, tmp_path
):
    """`elements = 1000000000` (the preloaded example's ball bearing): each element is a row
    of the law's arrays, 7.45 GiB of indices; refused by field in the file and by name in the
    Python API, before any work, instead of a MemoryError or a hang."""
    from rheolin.data import example_text
    from rheolin.errors import ModelError

    text = example_text("preloaded")
    assert text.count("elements = 9") == 1
    (tmp_path / "big.toml").write_text(text.replace("elements = 9", "elements = 1000000000"))
    _refused(invoke("validate", tmp_path / "big.toml"),
             "shafts[0].rolling_bearings[0].elements", "1000")  # fmt: skip
    m = rl.Model()
    m.add_rigid_body("r", (0, 0, 0), 1.0, (1e-3, 1e-3, 2e-3))
    with pytest.raises(ModelError, match=r"`elements` must be an integer from 3 to 1000"):
        m.add_rolling_bearing("A", "r", 0, kind="ball", stiffness=8e9, elements=10**9)
    m.add_rolling_bearing("A", "r", 0, kind="ball", stiffness=8e9, elements=1000)  # the limit
