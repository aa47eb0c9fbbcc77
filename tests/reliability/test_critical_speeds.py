"""Undamped critical speeds on anisotropic supports: each plane's straight-line (or elliptic)
mode is excited by unbalance and is a critical speed; the console table of ``rheolin
critical-map`` against the closed form of a rigid rotor on springs and against the Campbell
diagram's 1x crossings of the example rotor."""

from __future__ import annotations

import re

import numpy as np
import pytest

from rheolin.mechanics import Model
from rheolin.stability.campbell import campbell
from rheolin.stability.critical_map import synchronous_critical_speeds

M, ID, IP = 10.0, 0.1, 0.15  # I_p > I_d: no forward tilt critical
KX, KY, KZ, KT = 4.0e6, 9.0e6, 2.0e7, 5.0e5

RIGID = f"""
[model]
speed = "1000 rpm"

[[rigid_bodies]]
name = "r"
position = [0, 0, 0]
mass = {M}
inertia = [{ID}, {ID}, {IP}]

[[rigid_bodies.disks]]
node = 0
unbalance = "1 g*mm"

[[rigid_bodies.bearings]]
name = "b"
node = 0
components = "all"
stiffness = [{KX}, {KY}, {KZ}, {KT}, {KT}, 1e4]
"""


def _rigid_rotor() -> Model:
    m = Model()
    m.add_rigid_body("r", (0, 0, 0), M, (ID, ID, IP))
    m.add_bearing("b", "r", 0, stiffness=[KX, KY, KZ, KT, KT, 1e4], components=None)
    return m


def test_rigid_rotor_on_anisotropic_springs_has_both_translation_criticals() -> None:
    """Translation in x at ``sqrt(k_x / m)`` and in y at ``sqrt(k_y / m)`` (straight lines,
    whirl ratio 0, both excited by unbalance); the backward tilt, the axial and the torsional
    modes are not critical speeds (the axial one coincides with the backward tilt here,
    sqrt(k_z / m) = sqrt(k_t / (I_d + I_p)): the pair does not whirl forward)."""
    got = synchronous_critical_speeds(_rigid_rotor(), 6)
    want = np.sqrt([KX / M, KY / M])
    assert got.size == 2, got
    assert np.allclose(got, want, rtol=1e-10), (got, want)


def test_console_table_lists_the_closed_form_criticals(invoke, tmp_path) -> None:
    (tmp_path / "r.toml").write_text(RIGID)
    res = invoke("critical-map", tmp_path / "r.toml", "--out", tmp_path / "o", "--count", "3")
    assert res.exit_code == 0, res.stderr
    rows = re.findall(r"│\s+(\d)\s+│\s+([0-9.]+)\s+│", res.stdout)
    rpm = [float(v) for _, v in rows]
    want = np.sqrt([KX / M, KY / M]) * 30 / np.pi
    assert len(rpm) == 2 and np.allclose(rpm, want, rtol=1e-4), (rpm, want)


@pytest.mark.parametrize("model_name", ["rotor"])
def test_example_rotor_criticals_are_the_campbell_crossings(model_name, rotor) -> None:
    """The example rotor (cross-coupled, anisotropic bearings): its first two critical speeds
    are the Campbell diagram's 1x crossings near 4,220 rpm (the example's header), not the
    tens of thousands of rpm of a forward-only filter."""
    from rheolin.io import load_model

    model = load_model(rotor)
    got = synchronous_critical_speeds(model, 2) * 30 / np.pi
    rpm = np.linspace(4100.0, 4340.0, 25)
    diagram = campbell(model, rpm * np.pi / 30)
    lateral = sorted(
        c.speed * 30 / np.pi
        for c in diagram.critical_speeds
        if c.order == "1x rotor" and c.kind.startswith("lateral")
    )
    assert len(lateral) == 2, diagram.critical_speeds
    # damping is left out of the map (500 N s/m: a frequency shift of about zeta^2 / 2)
    assert np.allclose(got, lateral, rtol=2e-4), (got, lateral)
    assert 4100 < got[0] < 4340


def test_large_model_criticals_by_arnoldi_are_those_of_qz(monkeypatch) -> None:
    """Above ``DENSE_CRITICAL`` unknowns the lowest roots come by shift-invert Arnoldi on a
    sparse LU: the example rotor meshed to 101 shaft nodes (606 DOF) gives the critical speeds
    of QZ on the whole pencil. Its torsional mode at 3,998 rpm (no whirl; Arnoldi leaves
    rounding's 1e-13 of a whirl on it) is not one."""
    import rheolin.stability.critical_map as cm
    from rheolin.data.fine import refined_example
    from rheolin.io import parse_model

    model = parse_model(refined_example("rotor", 101)).model
    sparse = synchronous_critical_speeds(model, 4)
    monkeypatch.setattr(cm, "DENSE_CRITICAL", 10**6)
    dense = synchronous_critical_speeds(model, 4)
    assert sparse.size == dense.size == 4
    assert np.allclose(sparse, dense, rtol=1e-9), (sparse, dense)
    assert 4200 < sparse[0] * 30 / np.pi < 4240  # the example's 1x crossings near 4,220 rpm
