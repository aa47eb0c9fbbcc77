"""Open exponents confirmed on a lattice grown along the steps they leak to
(``rheolin.floquet.confirm.grown_lattice``; docs/stability.md, section 4), against the
monodromy matrix of the gear variant (gear_variants.py).

Below its ranges (3000 rpm) the variant's order-1 lattice leaves heavily damped clusters
unresolved, far left of the leading exponent: they are confirmed on the grown lattice, and
the verdict must still be the reference's. Inside its principal range the open exponents
include the growing one, near the axis, where a grown lattice lost it (decided stable at
3825 rpm): there the confirmations keep the standard orders
(tests/stability/test_runup_edge.py holds that case).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import rheolin as rl
from rheolin.floquet.confirm import standard_lattices

sys.path.insert(0, str(Path(__file__).parent))
from gear_variants import reference_ranges, variant_model

RPM = 30 / np.pi


def test_grown_confirmation_against_the_monodromy_matrix() -> None:
    """3000 rpm: the first confirmation is on the grown lattice, smaller than order 2, and
    settles every open cluster (kept); the verdict is decided stable and its largest real
    part is the monodromy matrix's within the stated uncertainties."""
    (point,) = [p for p in reference_ranges()["points"] if p["rpm"] == 3000.0]
    res = rl.floquet(variant_model().assemble(3000.0 / RPM).system)
    first = res.info["confirmed"][0]
    assert first["grown"] and first["kept"] and first["clusters"] > 0
    assert res.lattice is not None and res.lattice.order == 1
    (order2, _) = standard_lattices(res.lattice)
    assert first["harmonics"] < len(order2)
    assert all(step["kept"] for step in res.info["confirmed"])
    assert res.decided and res.stable
    assert abs(res.max_real - point["max_real"]) <= res.max_real_uncertainty + point["error"]
