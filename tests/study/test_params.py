"""Parameter paths and values (``--vary``): resolution against the model file, ranges and
lists, and refusals that name the field."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from rheolin.data import example_path, example_text
from rheolin.io import load_model
from rheolin.study import ParameterError, StudySpec
from rheolin.study.params import apply, parse_vary


@pytest.fixture(scope="module")
def gearbox():
    return tomllib.loads(example_text("gearbox"))


@pytest.mark.parametrize(
    ("path", "field", "value"),
    [
        ("bearings.input_A.stiffness", "shafts[0].bearings[0].stiffness", None),
        ("bearings.output_B.stiffness[0][1]", "shafts[2].bearings[1].stiffness[0][1]", "3e7 N/m"),
        (
            "shafts.intermediate.bearings.intermediate_B.damping[1]",
            "shafts[1].bearings[1].damping[1]",
            "2000 N*s/m",
        ),
        ("meshes.stage2.damping", "meshes[1].damping", "2500 N*s/m"),
        (
            "meshes[0].transmission_error[0].amplitude",
            "meshes[0].transmission_error[0].amplitude",
            "3 um",
        ),
        ("shafts.intermediate.section.Iy", "shafts[1].section.Iy", "11.094 cm^4"),
        ("shafts[2].disks[0].unbalance", "shafts[2].disks[0].unbalance", "150 g*mm"),
        ("bodies.input.material_damping", "shafts[0].material_damping", "2e-6 s"),
        ("model.gravity[1]", "model.gravity[1]", "-9.81 m/s^2"),
        ("harmonics.order", "harmonics.order", 3),
    ],
)
def test_paths_follow_the_file_and_name_its_items(gearbox, path, field, value):
    p = parse_vary(f"{path}=1,2", gearbox)
    assert p.field == field
    node = gearbox
    for key in p.location:
        node = node[key]
    if value is not None:
        assert node == value  # the value the path points at in the file
    changed = apply(gearbox, [(p, 1)])
    node = changed
    for key in p.location:
        node = node[key]
    assert node == 2 and p.integer  # written as the file would, the original untouched
    assert apply(gearbox, [])["meshes"] == gearbox["meshes"]


def test_a_range_takes_count_values_and_units(gearbox):
    p = parse_vary("bearings.input_A.stiffness=1e8:4e8:7 N/m", gearbox)
    np.testing.assert_array_equal(p.values, np.linspace(1e8, 4e8, 7))
    assert (p.unit, p.integer, p.entry(0)) == ("N/m", False, "100000000.0 N/m")
    q = parse_vary("meshes.stage1.stiffness_harmonics=3:7:5", gearbox)
    assert q.values == (3, 4, 5, 6, 7) and q.integer and q.entry(4) == 7
    r = parse_vary("meshes.stage1.damping=500 N*s/m, 1.5e3 N*s/m", gearbox)
    assert r.values == (500.0, 1500.0) and r.unit == "N*s/m"


def test_a_varied_value_reaches_the_model():
    """The value written into the file's data is what the built model holds (SI)."""
    spec = StudySpec.create(
        example_path("gearbox"), [300.0], ["bearings.input_A.stiffness[1][1]=1e8,3e8 N/mm"]
    )
    base = load_model(example_path("gearbox")).joints["input_A"]["K"]
    K = spec.loaded(1).model.joints["input_A"]["K"]
    assert K[1, 1] == 3e11
    K[1, 1] = base[1, 1]
    np.testing.assert_array_equal(K, base)  # nothing else changed


BAD = [
    ("bearings.input_X.stiffness=1:2:3", "bearings.input_X.stiffness", "no bearing named"),
    ("bearings.input_A.stifness=1:2:3", "bearings.input_A.stifness", "unknown key 'stifness'"),
    ("meshes.stage3.damping=1,2", "meshes.stage3.damping", "named 'stage3'"),
    ("shafts[7].density=1,2", "shafts[7].density", "has 3 entries"),
    ("meshes.stage1.damping=2e3:1e3:5", "meshes.stage1.damping", "backwards"),
    ("meshes.stage1.damping=1e3:1e3:5", "meshes.stage1.damping", "empty"),
    ("meshes.stage1.damping=1e3:2e3:0", "meshes.stage1.damping", "empty"),
    ("meshes.stage1.damping=1e3:2e3:2.5", "meshes.stage1.damping", "whole number"),
    ("meshes.stage1.damping=1e3,1e3", "meshes.stage1.damping", "repeat"),
    ("meshes.stage1.damping=1 N*s/m, 2 kN*s/m", "meshes.stage1.damping", "one unit"),
    ("meshes.stage1.damping=", "meshes.stage1.damping", "no values"),
    ("model.speed=1000,2000 rpm", "model.speed", "--speeds"),
    ("bearings.input_A.stiffness[5]=1,2", "bearings.input_A.stiffness[5]", "no entry [5]"),
]


@pytest.mark.parametrize(("text", "path", "words"), BAD, ids=[b[0] for b in BAD])
def test_bad_specifications_name_the_path_in_one_line(gearbox, text, path, words):
    with pytest.raises(ParameterError) as err:
        parse_vary(text, gearbox)
    message = str(err.value)
    assert message.startswith(path) and words in message and "\n" not in message


@pytest.mark.parametrize(
    ("vary", "words"),
    [
        # units and signs are checked by the model file's validation, naming its field
        ("meshes.stage1.damping=1,2 kg", "meshes[0].damping: expected a damping in N*s/m"),
        ("shafts.output.density=-1,1 kg/m^3", "shafts[2].density: must be >= 0"),
        ("bearings.input_A.stiffness=1,2 N*m/rad", "shafts[0].bearings[0].stiffness"),
        # tooth counts change the base frequency: a study keeps the harmonic numbering
        ("meshes.stage1.gear_teeth=67,68", "changes the speed ratios"),
    ],
)
def test_values_are_validated_like_the_model_file(vary, words):
    with pytest.raises(ParameterError) as err:
        StudySpec.create(example_path("gearbox"), [300.0], [vary])
    assert words in str(err.value) and "\n" not in str(err.value)
    assert str(err.value).startswith(vary.split("=")[0])


def test_the_key_changes_with_everything_that_decides_a_result(tmp_path):
    from rheolin.study import Settings

    model = tmp_path / "rotor.toml"
    model.write_text(example_text("rotor"))
    base = StudySpec.create(model, [300.0, 400.0], ["bearings.free_end.damping=500,800"])
    same = StudySpec.create(model, [400.0, 300.0], {"bearings.free_end.damping": [500, 800]})
    assert same.key == base.key  # speeds are sorted; a list or a string gives the same values
    others = [
        StudySpec.create(model, [300.0, 401.0], ["bearings.free_end.damping=500,800"]),
        StudySpec.create(model, [300.0, 400.0], ["bearings.free_end.damping=500,801"]),
        StudySpec.create(model, [300.0, 400.0], ["bearings.drive_end.damping[0]=500,800"]),
        StudySpec.create(
            model, [300.0, 400.0], ["bearings.free_end.damping=500,800"], Settings(order=3)
        ),
    ]
    assert len({s.key for s in others} | {base.key}) == 5
    for s in others:
        assert base.difference(s.identity())
    model.write_text(example_text("rotor") + "\n# an edit\n")
    edited = StudySpec.create(model, [300.0, 400.0], ["bearings.free_end.damping=500,800"])
    assert "model file changed" in base.difference(edited.identity())
