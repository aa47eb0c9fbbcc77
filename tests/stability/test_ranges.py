"""Unstable speed ranges against the monodromy matrix (issue 30).

The gearbox variant of gear_variants.py has a principal parametric resonance of its polymer
second mesh (about 3439-3890 rpm) and a combination resonance of two modes carrying it (about
4460-5040 rpm); their bounds are stored from monodromy matrices to 1e-6 relative
(gear_variants.py --regenerate). What must hold:

* the bounds of ``stability_map`` and ``rheolin sweep`` within 1e-4 relative of the
  reference, each with a stated uncertainty that covers it;
* no speed whose verdict is undecided is reported stable;
* ``rl.floquet(..., rtol=)`` meets the requested accuracy of the largest real part, and the
  default is 1e-4 relative near a resonance.

The maps run without refining each sample's largest real part (``rtol=inf``): the bounds
do not depend on it, and the default accuracy has its own test.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

import rheolin as rl
from rheolin.stability import stability_map

sys.path.insert(0, str(Path(__file__).parent))
from gear_variants import reference_ranges, variant_model, variant_toml

RPM = 30 / np.pi

#: Sample speeds [rpm] of each range's map: every 100 rpm around it.
WINDOWS = {
    "principal": np.arange(3300.0, 4001.0, 100.0),
    "combination": np.arange(4300.0, 5201.0, 100.0),
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


@pytest.mark.parametrize("name", ["principal", "combination"])
def test_map_bounds_against_the_monodromy_matrix(model, reference, name: str) -> None:
    """One range per window; each bound within 1e-4 relative of the monodromy matrix's,
    with a stated uncertainty (at most 1e-4 relative) that covers the reference."""
    ref = reference["ranges"][name]
    rpm = WINDOWS[name]
    smap = stability_map(model, rpm / RPM, rtol=np.inf)
    (r,) = smap.ranges
    assert not r.lower_open and not r.upper_open
    for side in ("lower", "upper"):
        got = getattr(r, side) * RPM
        unc = getattr(r, f"{side}_uncertainty") * RPM
        truth, truth_unc = ref[f"{side}_rpm"], ref[f"{side}_uncertainty_rpm"]
        assert got == pytest.approx(truth, rel=1e-4), side
        assert unc <= 1e-4 * truth, side
        assert abs(got - truth) <= unc + truth_unc, side
    # every sample decided, and on the reference's side of the bounds
    inside = (rpm > ref["lower_rpm"]) & (rpm < ref["upper_rpm"])
    assert np.all(smap.decided)
    assert np.array_equal(~smap.stable, inside)


def test_no_undecided_speed_is_reported_stable(model) -> None:
    """Next to and inside the principal range, on the 126-DOF variant too: a speed is
    reported stable only with a decided verdict, and (on the 72-DOF variant, whose reference
    this is) no decided verdict is on the wrong side of the monodromy matrix's bounds; an
    undecided one is its own state."""
    ref = reference_ranges()["ranges"]["principal"]
    rpm = np.array([3300.0, 3439.5, 3700.0, 3874.0, 3900.0])
    inside = (rpm > ref["lower_rpm"]) & (rpm < ref["upper_rpm"])
    for m in (model, variant_model(coarse=False)):
        smap = stability_map(m, rpm / RPM, refine=0.0, rtol=np.inf, identify_mechanism=False)
        undecided = ~np.asarray(smap.decided, bool)
        assert not np.any(smap.stable & undecided)
        assert [str(s) for s in smap.state[undecided]] == ["undecided"] * int(undecided.sum())
        if m is model:
            assert not np.any(smap.stable & inside)
            assert not np.any((smap.state == "unstable") & ~inside)


@pytest.mark.parametrize("rpm", [3700.0, 4800.0])
def test_floquet_rtol_meets_the_monodromy_matrix(model, reference, rpm: float) -> None:
    """``rtol=1e-6``: the largest real part (a growth rate, what variants are compared by)
    within 1e-6 relative of the monodromy matrix, and its stated uncertainty as small."""
    p = _point(reference, rpm)
    res = rl.floquet(model.assemble(rpm / RPM).system, rtol=1e-6)
    assert res.decided and not res.stable
    assert res.max_real == pytest.approx(p["max_real"], rel=1e-6, abs=p["error"])
    assert res.max_real_uncertainty <= 1e-6 * abs(res.max_real)


@pytest.mark.parametrize("rpm", [3420.0, 3700.0, 3880.0, 4480.0, 4800.0, 5020.0])
def test_default_accuracy_near_the_ranges(model, reference, rpm: float) -> None:
    """Without ``rtol``: decided, on the right side, and the largest real part within 1e-4
    relative of the monodromy matrix next to and inside both ranges."""
    p = _point(reference, rpm)
    res = rl.floquet(model.assemble(rpm / RPM).system)
    assert res.decided and res.stable == (p["max_real"] < 0)
    assert res.max_real == pytest.approx(p["max_real"], rel=1e-4, abs=p["error"])


def test_sweep_reports_bounds_with_uncertainties(reference, tmp_path: Path) -> None:
    """``rheolin sweep`` across the principal range: sweep.json's range within 1e-4 relative
    of the monodromy matrix, its uncertainties in rpm, every speed's state a decided one."""
    sys.path.insert(0, str(Path(__file__).parents[1] / "cli"))
    from test_cli import cli

    ref = reference["ranges"]["principal"]
    path = tmp_path / "variant.toml"
    path.write_text(variant_toml())
    out = tmp_path / "sweep"
    res = cli("sweep", str(path), "--speeds", "3300:4000:100rpm", "--out", str(out))
    assert res.returncode == 1, res.stderr  # an unstable range
    table = json.loads((out / "sweep.json").read_text())
    (r,) = table["unstable_ranges"]
    for side in ("lower", "upper"):
        assert r[f"{side}_rpm"] == pytest.approx(ref[f"{side}_rpm"], rel=1e-4)
        assert (
            abs(r[f"{side}_rpm"] - ref[f"{side}_rpm"])
            <= r[f"{side}_uncertainty_rpm"] + ref[f"{side}_uncertainty_rpm"]
        )
    assert set(table["stability"]) <= {"stable", "unstable"}
