"""The drawing of a planetary set (the wind-turbine example's 21/39/99 stage, normal module
10 mm, helix 7.5 deg): its gears at their pitch diameters ``z m / cos(beta)``, each planet's sun
and ring meshes, and a gear-train view that the 47 m rotor on the same axis does not dwarf."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rheolin.data import example_path
from rheolin.io import load_model
from rheolin.plots.drawing import model_figure
from rheolin.plots.geometry import model_geometry


def test_planetary_set_is_drawn_to_scale():
    model = load_model(example_path("wind-turbine"))
    geo = model_geometry(model)
    mt = 0.010 / math.cos(math.radians(7.5))
    meshes = {m.name: m for m in geo.meshes}
    for n in range(3):
        sun, ring = meshes[f"stage1.sun{n}"], meshes[f"stage1.ring{n}"]
        assert (sun.pinion_pitch, sun.gear_pitch) == pytest.approx((21 * mt, 39 * mt), rel=1e-12)
        assert ring.internal and ring.gear_pitch == pytest.approx(99 * mt, rel=1e-12)
        # the planets on the carrier at the sun-planet centre distance, 120 deg apart
        radial = (sun.gear_centre - sun.pinion_centre)[:2]
        assert np.linalg.norm(radial) == pytest.approx((21 + 39) * mt / 2, rel=1e-9)
        assert ring.pinion_centre == pytest.approx(sun.gear_centre)
        if n:
            first = (meshes["stage1.sun0"].gear_centre - sun.pinion_centre)[:2]
            cos = radial @ first / np.linalg.norm(radial) / np.linalg.norm(first)
            assert cos == pytest.approx(-0.5, abs=1e-9)
    teeth = sorted(d.teeth for d in geo.disks if d.mesh is not None and "stage1" in d.mesh)
    assert teeth == [21, 39, 39, 39, 99]
    end = model_figure(model).axes[1]
    assert max(abs(v) for v in (*end.get_xlim(), *end.get_ylim())) < 1500.0  # mm, not the rotor
