"""Open exponents confirmed on a lattice grown along the steps they leak to
(``rheolin.floquet.grown.grown_lattice``; docs/stability.md, section 4), against the
monodromy matrix of the gear variant (gear_variants.py).

Below its ranges (3000 rpm) the variant's order-1 lattice leaves heavily damped clusters
unresolved, far left of the leading exponent: they are confirmed on the grown lattice, and
the verdict must still be the reference's. Where order 2 leaves some open too, far left,
the next step is first on the lattice grown one order along their leaks
(``grown_further``): the gearbox at 500 rpm against order 3; the variant with the example's
steel second stage, whose leak one more order would not extend, against its monodromy
matrix. Inside its principal range the open exponents include the growing one, near the
axis, where a grown lattice lost it (decided stable at 3825 rpm): there the confirmations
keep the standard orders (tests/stability/test_runup_edge.py holds that case).
"""

from __future__ import annotations

import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

import rheolin as rl
from rheolin.floquet import lattice_run
from rheolin.floquet.confirm import lattice_order, standard_lattices

sys.path.insert(0, str(Path(__file__).parent))
from gear_variants import STEEL, reference_ranges, steel_reference, variant_model

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


def test_no_growth_along_a_step_one_order_would_not_extend() -> None:
    """The steel variant at 500 rpm: order 2 leaves a cluster open, far left, leaking along a
    mesh harmonic that order 2 holds at cost 2; one more order would not extend that step
    (only relabel its harmonics off the edge the resolution test reads), so the standard
    order 3 settles it. Decided stable, the largest real part the monodromy matrix's."""
    (point,) = [p for p in steel_reference()["points"] if p["rpm"] == 500.0]
    res = rl.floquet(variant_model(**STEEL).assemble(500.0 / RPM).system)
    steps = res.info["confirmed"]
    assert [(s["order"], s["grown"]) for s in steps] == [(2, True), (2, False), (3, False)]
    assert all(s["kept"] for s in steps)
    assert res.decided and res.stable
    assert abs(res.max_real - point["max_real"]) <= res.max_real_uncertainty + point["error"]


def test_grown_further_against_order_3(monkeypatch: pytest.MonkeyPatch) -> None:
    """The gearbox at 500 rpm: after order 2 two heavily damped clusters stay open, far left
    of the leading exponent, leaking along cost-1 steps; the lattice grown one order along
    them (fewer harmonics than order 3) settles them and is kept. The verdict is that of the
    standard order 3 (no monodromy matrix: the gearbox's common period is 4,757
    revolutions), and each exponent settled on the grown lattice is one of order 3's within
    the two uncertainties."""
    from rheolin.data import example_text
    from rheolin.io import parse_document

    system = (
        parse_document(tomllib.loads(example_text("gearbox"))).model.assemble(500.0 / RPM).system
    )
    res = rl.floquet(system)
    steps = res.info["confirmed"]
    grown = [s for s in steps if s["order"] == 6]
    assert len(grown) == 1 and grown[0]["grown"] and grown[0]["kept"] and grown[0]["replaced"]
    assert steps[-1] is grown[0]
    assert res.lattice is not None
    order3 = lattice_order(res.lattice, 3)
    assert order3 is not None and grown[0]["harmonics"] < len(order3)
    assert res.decided and res.stable

    monkeypatch.setattr(lattice_run, "grown_further", lambda *args: None)
    standard = rl.floquet(system)
    assert standard.info["confirmed"][-1]["order"] == 3
    assert standard.decided and standard.stable
    both = res.max_real_uncertainty + standard.max_real_uncertainty
    assert abs(res.max_real - standard.max_real) <= both
    mine = np.asarray(res.info["order"]) == 6
    assert mine.any()
    tol = np.asarray(res.info["uncertainty"])
    tol3 = np.asarray(standard.info["uncertainty"])
    for z, dz in zip(res.exponents[mine], tol[mine], strict=True):
        gap = np.abs(standard.exponents - z)
        i = int(np.argmin(gap))
        assert gap[i] <= dz + tol3[i], (z, standard.exponents[i], dz, tol3[i])
