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
