"""Unstable speed ranges against the monodromy matrix (issue 30).

The gearbox variant of gear_variants.py has a principal parametric resonance of its polymer
second mesh (3439.46-3877.13 rpm) and a combination resonance of two modes carrying it
(4449.17-5042.91 rpm); their bounds are stored from monodromy matrices to 1e-7 relative
(gear_variants.py --regenerate). What must hold:

* a range edge of ``stability_map`` within 1e-4 relative of the reference, with a stated
  uncertainty that covers it, from samples on either side of the edge (20 rpm apart, to keep
  the test to a few verdicts; bench/stability.py refines all four edges from samples 100 rpm
  apart);
* ``rl.floquet(..., rtol=)`` meets the requested accuracy of the largest real part, and the
  default is 1e-4 relative next to a range, where the lattice of coupling costs alone
  decided it wrongly.

That no undecided verdict is reported stable: tests/study/test_undecided.py.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import rheolin as rl
from rheolin.stability import stability_map

sys.path.insert(0, str(Path(__file__).parent))
from gear_variants import reference_ranges, variant_model

RPM = 30 / np.pi

#: Samples [rpm] on either side of an edge, per (range, edge): the principal resonance's
#: lower edge (the growing exponent rises like a square root past the lock of the pair) and
#: the combination resonance's upper edge (a smooth crossing, undecided within +-5 rpm of it
#: at lattice order 1).
EDGES = {
    ("principal", "lower"): (3430.0, 3450.0),
    ("combination", "upper"): (5030.0, 5050.0),
}


@pytest.fixture(scope="module")
def model() -> rl.Model:
    return variant_model()


@pytest.fixture(scope="module")
def reference() -> dict:
    return reference_ranges()


def _point(reference: dict, rpm: float) -> dict:
    (p,) = [p for p in reference["points"] if p["rpm"] == rpm]
    return p


@pytest.mark.parametrize(("name", "side"), sorted(EDGES))
def test_edge_against_the_monodromy_matrix(model, reference, name: str, side: str) -> None:
    """The edge within 1e-4 relative of the monodromy matrix's, with a stated uncertainty
    (at most 1e-4 relative) that covers the reference; both samples decided on their
    reference sides."""
    ref = reference["ranges"][name]
    rpm = np.array(EDGES[name, side])
    smap = stability_map(model, rpm / RPM, refine=5e-5, rtol=np.inf, identify_mechanism=False)
    (r,) = smap.ranges
    got = getattr(r, side) * RPM
    unc = getattr(r, f"{side}_uncertainty") * RPM
    truth, truth_unc = ref[f"{side}_rpm"], ref[f"{side}_uncertainty_rpm"]
    assert got == pytest.approx(truth, rel=1e-4)
    assert unc <= 1e-4 * truth
    assert abs(got - truth) <= unc + truth_unc
    inside = (rpm > ref["lower_rpm"]) & (rpm < ref["upper_rpm"])
    assert list(smap.state) == ["unstable" if x else "stable" for x in inside]


def test_floquet_rtol_meets_the_monodromy_matrix(model, reference) -> None:
    """``rtol=1e-6`` just inside the combination range: the largest real part (a growth
    rate, what variants are compared by) within 1e-6 relative of the monodromy matrix, and
    its stated uncertainty as small."""
    p = _point(reference, 4480.0)
    res = rl.floquet(model.assemble(4480.0 / RPM).system, rtol=1e-6)
    assert res.decided and not res.stable
    assert res.max_real == pytest.approx(p["max_real"], rel=1e-6, abs=p["error"])
    assert res.max_real_uncertainty <= 1e-6 * abs(res.max_real)
    # the memory it reports covers the finer lattices the refinement searched (near the
    # leading cluster: one cluster at least)
    from rheolin.floquet.confirm import lattice_order
    from rheolin.floquet.footprint import lattice_memory

    orders = res.info["accuracy"]["orders"]
    assert orders
    finest = lattice_order(res.lattice, max(orders))
    system = model.assemble(4480.0 / RPM).system
    assert res.info["memory_estimate"] >= lattice_memory(system, finest, clusters=1)


def test_default_accuracy_next_to_a_range(model, reference) -> None:
    """Without ``rtol``: decided stable and the largest real part within 1e-4 relative of
    the monodromy matrix 3 rpm above the principal range (where the lattice of coupling
    costs alone decided stable with -47.9 1/s: the growing mode's cluster was filled by
    another mode's copy)."""
    p = _point(reference, 3880.0)
    res = rl.floquet(model.assemble(3880.0 / RPM).system)
    assert res.decided and res.stable
    assert res.max_real == pytest.approx(p["max_real"], rel=1e-4, abs=p["error"])
    assert res.max_real_uncertainty <= 1e-4 * abs(res.max_real)
