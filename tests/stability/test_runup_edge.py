"""A run-up's verdicts next to the upper edge of the gear variant's principal range, continued
from speed to speed, against the monodromy reference range (gear_variants.py; issue 30).

Within 30 rpm below the edge (3877.13 rpm) the two exponents of the resonant pair are locked
at ``Im = 36 w1``; the search continued from the previous speed keeps the decaying one and
misses the growing one, and its cluster comes back short. The verdict must still be decided
unstable, as the reference says, and on the order-1 lattice: the short cluster is searched
again on the finer lattices near it (docs/stability.md, section 4), not the whole lattice
(the whole lattice at order 3 costs 30-50 times a steady-state solve there).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import rheolin as rl
from rheolin.floquet import Continuation

sys.path.insert(0, str(Path(__file__).parent))
from gear_variants import reference_ranges, variant_model

RPM = 30 / np.pi


def test_continued_verdicts_below_the_upper_edge_are_decided_on_order_one() -> None:
    """3825 then 3850 rpm with one continuation: decided unstable (inside the reference
    range), the growing exponent found, on the order-1 lattice."""
    edges = reference_ranges()["ranges"]["principal"]
    model = variant_model()
    cont = Continuation()
    for rpm in (3825.0, 3850.0):
        assert edges["lower_rpm"] < rpm < edges["upper_rpm"]
        res = rl.floquet(model.assemble(rpm / RPM).system, continuation=cont)
        assert res.decided and not res.stable, rpm
        assert res.max_real > 10 * res.max_real_uncertainty, rpm
        assert res.lattice is not None and res.lattice.order == 1, rpm
        assert "refined_from" not in res.info, rpm
