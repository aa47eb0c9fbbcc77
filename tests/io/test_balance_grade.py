"""An ISO 21940-11 balance grade in the model file: the disk's unbalance is the permissible
residual unbalance ``U = m G / W`` (ISO's ``U [g mm] = 9549 G m / n``), and bad combinations
are refused naming the field."""

from __future__ import annotations

import numpy as np
import pytest

from rheolin.errors import ModelError
from rheolin.io import parse_model

BASE = """
[model]
input_body = "r"
[[shafts]]
name = "r"
positions = "0 100 200 mm"
outer_diameter = "40 mm"
material = "steel"
disks = [{{ node = 1, {disk} }}]
[[shafts.bearings]]
name = "a"
node = 0
stiffness = "1e8 N/m"
"""


def _unbalance(disk: str) -> float:
    model = parse_model(BASE.format(disk=disk)).model
    (call,) = [c for c in model.calls if c[0] == "add_disk"]
    return float(call[1]["unbalance"])


def test_balance_grade_gives_the_iso_permissible_unbalance() -> None:
    u = _unbalance('mass = "100 kg", inertia = [1, 1, 2], balance_grade = "G6.3", '
                   'balance_speed = "3000 rpm"')  # fmt: skip
    assert u * 1e6 == pytest.approx(9549 * 6.3 * 100 / 3000, rel=1e-3)  # g mm, ISO's form
    # shared over a 400 kg rotor; a disk by its geometry (steel: 7850 kg/m^3)
    u = _unbalance('mass = "100 kg", inertia = [1, 1, 2], balance_grade = "G2.5", '
                   'balance_speed = "6000 rpm", balance_mass = "400 kg"')  # fmt: skip
    assert u == pytest.approx(400 * 2.5e-3 / (6000 * np.pi / 30), rel=1e-12)
    u = _unbalance('outer_diameter = "300 mm", width = "50 mm", balance_grade = "G1", '
                   'balance_speed = "100 rad/s"')  # fmt: skip
    assert u == pytest.approx(7850 * np.pi / 4 * 0.3**2 * 0.05 * 1e-3 / 100, rel=1e-12)


@pytest.mark.parametrize(
    "disk, match",
    [
        ('mass = 1.0, inertia = [1, 1, 1], balance_grade = "G6.3"', "balance_speed"),
        ('mass = 1.0, inertia = [1, 1, 1], balance_grade = "G7", balance_speed = 100.0', "G7"),
        ('mass = 1.0, inertia = [1, 1, 1], unbalance = 1e-4, balance_grade = "G1", '
         'balance_speed = 100.0', "not both"),
        ('mass = 1.0, inertia = [1, 1, 1], balance_speed = 100.0', "need balance_grade"),
    ],
)  # fmt: skip
def test_bad_balance_specifications_are_named(disk: str, match: str) -> None:
    with pytest.raises(ModelError, match=match) as info:
        parse_model(BASE.format(disk=disk))
    assert "disks[0]" in str(info.value)
