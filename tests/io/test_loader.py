"""Model files: units, one-to-one mapping onto the Python API, and refusal of broken files
with a message naming the field path."""

from __future__ import annotations

import re

import numpy as np
import pytest

import rheolin as rl
from rheolin.data import EXAMPLES, example_path, example_text
from rheolin.io import load_model, parse_model
from rheolin.io.units import to_si
from rheolin.mechanics.model import Model


@pytest.fixture(autouse=True)
def _allow_underflow():
    with np.errstate(under="ignore"):
        yield


def test_units_convert_to_si_and_hz_means_revolutions_per_second():
    assert to_si("3000 rpm", "speed") == pytest.approx(100 * np.pi)
    assert to_si("50 Hz", "speed") == pytest.approx(100 * np.pi)  # not 50 rad/s
    assert to_si("2e8 N/m", "stiffness") == 2e8
    assert to_si("5 g*mm", "unbalance") == pytest.approx(5e-6)
    assert to_si("35 mm", "length") == pytest.approx(0.035)
    assert to_si("1e4 N*m/rad", "rotational_stiffness") == pytest.approx(1e4)
    with pytest.raises(ValueError, match="N/m"):
        to_si("2e8 N*m", "stiffness")


def test_every_example_loads_and_docs_example_is_the_gearbox(tmp_path):
    for name in EXAMPLES:
        assert load_model(example_path(name)).bodies
    doc = (example_path("gearbox").parents[3] / "docs" / "model-format.md").read_text()
    blocks = re.findall(r"```toml\n(.*?)```", doc, flags=re.S)
    complete = [b for b in blocks if "[[meshes]]" in b and "[[shafts]]" in b]
    assert complete, "docs/model-format.md must contain a complete example"
    model = parse_model(complete[0]).model
    assert sorted(model.bodies) == ["input", "intermediate", "output"]


def _python_gearbox_stage() -> Model:
    """The same model as ``SMALL`` below, written with the Python API in SI units."""
    m = Model(input_body="a")
    m.add_shaft("a", [0.0, 0.05, 0.1], outer_diameter=0.03, material="steel")
    m.add_shaft(
        "b", [0.0, 0.05, 0.1], outer_diameter=0.04, origin=(0.06, 0.0, 0.0), material="steel"
    )
    m.add_disk("a", 1, outer_diameter=0.044, width=0.02, unbalance=5e-6, material="steel")
    m.add_disk("b", 1, mass=0.7706, inertia=(3.4e-4, 3.4e-4, 6.17e-4), unbalance=1e-5)
    for body in ("a", "b"):
        m.add_bearing(
            f"{body}0",
            body,
            0,
            [1e8, 1e8, 5e7, 1e3],
            [500, 500, 500, 1.0],
            ["ux", "uy", "uz", "phiz"],
        )
        m.add_bearing(f"{body}2", body, 2, [[2e8, 1e7], [1e7, 1.5e8]], 500.0)
    m.add_gear_mesh(
        "mesh",
        "a",
        1,
        "b",
        1,
        20,
        40,
        module=0.002,
        stiffness=3e8,
        damping=800.0,
        transmission_error={1: 1e-6},
    )  # 2 um peak
    return m


SMALL = """
[model]
input_body = "a"
speed = "2000 rpm"

[[shafts]]
name = "a"
positions = "0 50 100 mm"
outer_diameter = "30 mm"
material = "steel"            # E, nu and density of steel (disks too)
disks = [{ node = 1, outer_diameter = "44 mm", width = "20 mm", unbalance = "5 g*mm" }]

[[shafts.bearings]]
name = "a0"
node = 0
components = ["ux", "uy", "uz", "phiz"]
stiffness = ["1e8 N/m", "1e8 N/m", "5e7 N/m", "1e3 N*m/rad"]
damping = ["500 N*s/m", "500 N*s/m", "500 N*s/m", "1 N*m*s/rad"]

[[shafts.bearings]]
name = "a2"
node = 2
stiffness = [["2e8 N/m", "1e7 N/m"], ["1e7 N/m", "1.5e8 N/m"]]
damping = "500 N*s/m"

[[shafts]]
name = "b"
positions = [0.0, 0.05, 0.1]
origin = ["60 mm", 0, 0]
outer_diameter = 0.04
material = "steel"
disks = [{ node = 1, mass = 0.7706, inertia = [3.4e-4, 3.4e-4, 6.17e-4], unbalance = 1e-5 }]

[[shafts.bearings]]
name = "b0"
node = 0
components = ["ux", "uy", "uz", "phiz"]
stiffness = [1e8, 1e8, 5e7, 1e3]
damping = [500, 500, 500, 1.0]

[[shafts.bearings]]
name = "b2"
node = 2
stiffness = [[2e8, 1e7], [1e7, 1.5e8]]
damping = 500

[[meshes]]
name = "mesh"
pinion_body = "a"
pinion_node = 1
gear_body = "b"
gear_node = 1
pinion_teeth = 20
gear_teeth = 40
module = "2 mm"
stiffness = "3e8 N/m"
damping = "800 N*s/m"
transmission_error = [{ harmonic = 1, amplitude = "2 um" }]
"""


def test_file_maps_one_to_one_onto_the_python_api():
    from_file = parse_model(SMALL).model.assemble(2000 * np.pi / 30).system
    by_hand = _python_gearbox_stage().assemble(2000 * np.pi / 30).system
    assert from_file.coefficient_harmonics == by_hand.coefficient_harmonics
    assert from_file.load_harmonics == by_hand.load_harmonics
    for name in ("M", "D", "K"):
        for k in [*from_file.coefficient_harmonics, 0]:
            a, b = from_file.coefficient(name, k), by_hand.coefficient(name, k)
            assert (a is None) == (b is None)
            if a is not None:
                assert abs(a - b).max() <= 1e-9 * abs(b).max()
    scale = max(np.abs(by_hand.load(k)).max() for k in by_hand.load_harmonics)
    for k in from_file.load_harmonics:
        assert np.allclose(from_file.load(k), by_hand.load(k), rtol=0, atol=1e-12 * scale)
    assert rl.solve(from_file, rl.HarmonicSet.closure(from_file, 2)).success


def _broken(old: str, new: str, text: str = SMALL) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


BROKEN = [
    (
        "unknown key",
        _broken('outer_diameter = "30 mm"', 'outer_diametr = "30 mm"'),
        r"shafts\[0\]\.outer_diametr: unknown key; allowed keys here: .*outer_diameter",
    ),
    ("missing field", _broken('module = "2 mm"\n', ""), r"meshes\[0\]\.module: required"),
    (
        "wrong unit",
        _broken('stiffness = "3e8 N/m"', 'stiffness = "3e8 N*m"'),
        r"meshes\[0\]\.stiffness: expected a stiffness in N/m",
    ),
    (
        "wrong unit in a bearing matrix",
        _broken('"1.5e8 N/m"]]', '"1.5e8 kg"]]'),
        r"shafts\[0\]\.bearings\[1\]\.stiffness\[1\]\[1\]: expected a stiffness",
    ),
    (
        "negative mass",
        _broken(
            'disks = [{ node = 1, outer_diameter = "44 mm", width = "20 mm",',
            'disks = [{ node = 1, mass = "-1 kg", inertia = [1, 1, 1],',
        ),
        r"shafts\[0\]\.disks\[0\]\.mass: must be >= 0",
    ),
    (
        "non-symmetric mass matrix",
        _broken(
            'disks = [{ node = 1, outer_diameter = "44 mm", width = "20 mm",',
            "disks = [{ node = 1, mass = 1, inertia = [[1, 0.5, 0], [0, 1, 0], [0, 0, 2]],",
        ),
        r"shafts\[0\]\.disks\[0\]\.inertia: .*symmetric",
    ),
    (
        "indefinite mass matrix",
        _broken(
            'disks = [{ node = 1, outer_diameter = "44 mm", width = "20 mm",',
            "disks = [{ node = 1, mass = 1, inertia = [[1, 2, 0], [2, 1, 0], [0, 0, 2]],",
        ),
        r"shafts\[0\]\.disks\[0\]\.inertia: .*positive definite",
    ),
    (
        "missing node",
        _broken('name = "a2"\nnode = 2', 'name = "a2"\nnode = 7'),
        r"shafts\[0\]\.bearings\[1\]\.node: node 7 does not exist; body 'a' has nodes 0\.\.2",
    ),
    (
        "missing body",
        _broken('gear_body = "b"', 'gear_body = "c"'),
        r"meshes\[0\]\.gear_body: no body named 'c'",
    ),
    (
        "inconsistent teeth",
        _broken("gear_teeth = 40", "gear_teeth = 45"),
        r"meshes\[0\]\.gear_teeth: tooth counts 20\+45 with module 2 mm need .* 65 mm",
    ),
    (
        "bad input body",
        _broken('input_body = "a"', 'input_body = "x"'),
        r"model\.input_body: no body named 'x'",
    ),
]


@pytest.mark.parametrize(("what", "text", "pattern"), BROKEN, ids=[b[0] for b in BROKEN])
def test_broken_files_are_refused_naming_the_field(what, text, pattern):
    with pytest.raises(rl.ModelError, match=pattern):
        parse_model(text)


def test_examples_are_documented_text():
    assert "hunting tooth" in example_text("gearbox")


def test_condensed_body_from_a_matrix_file_relative_to_the_model(tmp_path):
    """A spinning disk given as condensed matrices (.npz next to the model file) on a bearing:
    the tilt whirl frequencies solve ``J_t w^2 -+ J_p W w - k_r = 0`` (Campbell API)."""
    from rheolin.io import read_model
    from rheolin.stability import campbell

    m, jt, jp, k, kr, W = 2.0, 0.01, 0.02, 4e5, 2e3, 300.0
    G = np.zeros((6, 6))
    G[3, 4], G[4, 3] = jp, -jp
    np.savez(tmp_path / "disk.npz", M=np.diag([m, m, m, jt, jt, jp]), K=np.zeros((6, 6)), G=G)
    (tmp_path / "sub").mkdir()
    text = f"""
[model]
input_body = "disk"

[[condensed_bodies]]
name = "disk"
positions = ["0 0 0 mm"]
path = "../disk.npz"

[[condensed_bodies.bearings]]
name = "support"
node = 0
components = "all"
stiffness = ["{k} N/m", "{k} N/m", "{k} N/m", "{kr} N*m/rad", "{kr} N*m/rad", "1e3 N*m/rad"]
"""
    (tmp_path / "sub" / "m.toml").write_text(text)
    model = read_model(tmp_path / "sub" / "m.toml").model
    res = campbell(model, [W])
    f, whirl = res.frequency[0], res.whirl[0]
    fwd = (jp * W + np.sqrt((jp * W) ** 2 + 4 * jt * kr)) / (2 * jt)
    bwd = (-jp * W + np.sqrt((jp * W) ** 2 + 4 * jt * kr)) / (2 * jt)
    assert np.min(np.abs(f[whirl == "forward"] - fwd)) < 1e-9 * fwd
    assert np.min(np.abs(f[whirl == "backward"] - bwd)) < 1e-9 * bwd
    assert np.min(np.abs(f - np.sqrt(k / m))) < 1e-9 * np.sqrt(k / m)
    (tmp_path / "sub" / "bad.toml").write_text(text.replace("../disk.npz", "nope.npz"))
    with pytest.raises(rl.ModelError, match=r"condensed_bodies\[0\]\.path: no such file"):
        read_model(tmp_path / "sub" / "bad.toml")
