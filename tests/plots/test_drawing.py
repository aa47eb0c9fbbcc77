"""The model drawing: the geometry it draws equals the model file's (pitch diameters z m,
centre distances, tube diameters recovered from a section's A and I), every example draws
without overlapping labels, and ``rheolin draw`` writes the file."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from rheolin.data import EXAMPLES, example_path
from rheolin.io import load_model
from rheolin.mechanics.sections import hollow_circular, rectangular
from rheolin.plots.drawing import model_figure
from rheolin.plots.geometry import model_geometry, section_diameters, support_kind
from rheolin.plots.layout import problems


def test_gear_pitch_diameters_and_centre_distances_of_the_gearbox():
    """Stage 1: module 2 mm, 23:67 (pitch 46 and 134 mm, centres 90 mm apart); stage 2:
    module 3 mm, 19:71 (57 and 213 mm, 135 mm): the file's layout, drawn to scale."""
    geo = model_geometry(load_model(example_path("gearbox")))
    meshes = {m.name: m for m in geo.meshes}
    for name, module, zp, zg in (("stage1", 0.002, 23, 67), ("stage2", 0.003, 19, 71)):
        m = meshes[name]
        assert (m.pinion_pitch, m.gear_pitch) == pytest.approx((zp * module, zg * module))
        distance = np.linalg.norm(m.gear_centre[:2] - m.pinion_centre[:2])
        assert distance == pytest.approx((zp + zg) * module / 2, rel=1e-12)
    gears = [d for d in geo.disks if d.mesh is not None]
    assert sorted(d.teeth for d in gears) == [19, 23, 67, 71]
    kinds = {s.name: s.kind for s in geo.supports}
    assert kinds["input_A"] == "radial+axial" and kinds["motor_coupling"] == "torsional"


def test_section_diameters_recover_a_tube_and_flag_a_flat():
    do, di, odd = section_diameters(hollow_circular(0.055, 0.02))
    assert (do, di, odd) == (pytest.approx(0.055, rel=1e-12), pytest.approx(0.02, rel=1e-9), False)
    d, _, odd = section_diameters(rectangular(0.02, 0.04))
    assert odd and d == pytest.approx(np.sqrt(4 * 0.02 * 0.04 / np.pi))


def test_support_kinds_from_components():
    assert support_kind(["ux", "uy"]) == "radial"
    assert support_kind(["uz", "phiz"]) == "axial+torsional"


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_every_example_draws_without_overlap(name):
    model = load_model(example_path(name))
    fig = model_figure(model, nodes=True)
    assert problems(fig) == []
    side = fig.axes[0]
    geo = model_geometry(model)
    # every shaft element is a patch of the side view, every disk too
    assert len(side.patches) >= len(geo.segments) + len(geo.disks)
    assert len(fig.axes) == (2 if geo.meshes else 1)


def test_draw_command_writes_png_and_svg(tmp_path):
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    for suffix in ("png", "svg"):
        out = tmp_path / f"d.{suffix}"
        res = subprocess.run(
            [sys.executable, "-m", "rheolin.cli", "draw", str(example_path("preloaded")),
             "--out", str(out), "--nodes"],
            capture_output=True, text=True, env=env, timeout=300,
        )  # fmt: skip
        assert res.returncode == 0, res.stderr
        head = out.read_bytes()[:8]
        assert head.startswith(b"\x89PNG") if suffix == "png" else b"<?xml" in head
    res = subprocess.run(
        [sys.executable, "-m", "rheolin.cli", "draw", str(tmp_path / "missing.toml")],
        capture_output=True, text=True, env=env, timeout=300,
    )  # fmt: skip
    assert res.returncode == 2


def test_condensed_body_and_bearings_between_bodies_are_drawn():
    """A shaft on two bearings to a condensed housing (two interface nodes), one of them
    with a rigid link: the housing's box, the springs between bodies and the link drawn."""
    import rheolin as rl

    m = rl.Model()
    m.add_shaft("s", np.linspace(0, 0.4, 5), outer_diameter=0.04, material="steel")
    K = np.kron(np.eye(2), np.diag([1e9, 1e9, 1e9, 1e7, 1e7, 1e7]))
    m.add_condensed_body("housing", [[0.0, -0.1, 0.0], [0.0, -0.1, 0.4]], M=10 * np.eye(12),
                         K=K, speed_ratio=0)  # fmt: skip
    for k, node in ((0, 0), (4, 1)):
        m.add_bearing(f"b{k}", "s", k, stiffness=1e8, other_body="housing", other_node=node)
    m.add_bearing("feet", "housing", 0, stiffness=1e9, components=None)
    m.add_rigid_link("tie", "s", 2, "housing", 1, components=["uz"])
    fig = model_figure(m, nodes=True)
    assert problems(fig) == []
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    for entry in ("condensed body", "bearing between bodies", "rigid link"):
        assert entry in labels
    texts = [t.get_text() for t in fig.axes[0].texts if t.get_visible()]
    assert "housing (condensed, 0 modes)" in texts
