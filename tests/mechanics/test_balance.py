"""ISO 21940-11 permissible residual unbalance: the standard's own form
``U_per [g mm] = 9549 G m / n`` (9549 = 60000 / 2 pi), and the meaning of a grade, the speed
``e_per W`` of the centre of mass in mm/s."""

from __future__ import annotations

import numpy as np
import pytest

from rheolin.errors import ModelError
from rheolin.mechanics.balance import GRADES, iso21940_unbalance


@pytest.mark.parametrize("grade", GRADES)
def test_grades_follow_the_standards_formula(grade):  # type: ignore[no-untyped-def]
    m, n = 37.0, 4500.0
    u = iso21940_unbalance(f"G{grade:g}", m, n * np.pi / 30)
    assert u * 1e6 == pytest.approx(60000 / (2 * np.pi) * grade * m / n, rel=1e-12)
    assert (u / m) * (n * np.pi / 30) * 1e3 == pytest.approx(grade, rel=1e-12)  # e W in mm/s


def test_bad_grades_and_inputs_are_named():  # type: ignore[no-untyped-def]
    with pytest.raises(ModelError, match="not an ISO 21940-11 grade"):
        iso21940_unbalance("G3", 1.0, 100.0)
    with pytest.raises(ModelError, match=r"write it like 'G2\.5'"):
        iso21940_unbalance("grade 2.5", 1.0, 100.0)
    with pytest.raises(ModelError, match="`speed`"):
        iso21940_unbalance(2.5, 1.0, 0.0)
    with pytest.raises(ModelError, match="`mass`"):
        iso21940_unbalance(2.5, -1.0, 100.0)
