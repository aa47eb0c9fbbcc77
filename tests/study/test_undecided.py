"""An undecided stability verdict is its own state in ``rheolin sweep`` (issue 30): never
``stable: true`` in sweep.json, its own flag in sweep.nc, named on the console, and a sweep
with one exits 1 (docs/stability.md: the exit-code rule).

The verdicts are the real ones of the band model (a rigid rotor on a spring fixed in its own
axes, unstable between 955 and 1050 rpm) except at two stable speeds, where the Floquet
result is made undecided the way a truncation that has not converged makes it (every
representative's energy at the edge of the dense Hill grid): what is reported must follow
``FloquetResult.decided``, whatever made it False.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from click.testing import Result
from typer.testing import CliRunner

from rheolin.cli import app

sys.path.insert(0, str(Path(__file__).parent))
from study_cases import BAND

import rheolin.solvers.solve  # noqa: F401  (the module, for its floquet)

solve_module = sys.modules["rheolin.solvers.solve"]

UNDECIDED_RPM = (900.0, 1200.0)


@pytest.fixture
def undecided_at(monkeypatch):
    """Make the verdicts at :data:`UNDECIDED_RPM` undecided (stable, not converged)."""
    real = solve_module.floquet

    def floquet(system, *args, **kwargs):
        res = real(system, *args, **kwargs)
        rpm = system.omega * 30 / np.pi  # the band model's w1 is its speed
        if any(abs(rpm - x) < 1e-6 for x in UNDECIDED_RPM):
            assert res.stable and res.method == "dense"
            res.converged = False
            res.edge_weight = np.ones_like(res.edge_weight)
            assert not res.decided
        return res

    monkeypatch.setattr(solve_module, "floquet", floquet)


def _sweep_band(tmp_path: Path) -> tuple[Result, Path]:
    """``rheolin sweep`` of the band model over 850-1250 rpm (in this process, where the
    patched verdicts apply): the result and the output directory."""
    model = tmp_path / "band.toml"
    model.write_text(BAND)
    out = tmp_path / "out"
    res = CliRunner().invoke(
        app,
        ["sweep", str(model), "--speeds", "850:1250:50rpm", "--out", str(out), "--workers", "1"],
        catch_exceptions=False,
    )
    return res, out


def test_sweep_reports_undecided_speeds(undecided_at, tmp_path: Path) -> None:
    res, out = _sweep_band(tmp_path)
    assert res.exit_code == 1, res.output
    table = json.loads((out / "sweep.json").read_text())
    rpm = np.round(np.array(table["speeds_rpm"]), 6)
    undecided = np.isin(rpm, UNDECIDED_RPM)
    assert [table["stable"][i] for i in np.flatnonzero(undecided)] == [None, None]
    assert [table["stability"][i] for i in np.flatnonzero(undecided)] == ["undecided"] * 2
    assert "undecided" not in [table["stability"][i] for i in np.flatnonzero(~undecided)]
    with xr.open_dataset(out / "sweep.nc") as ds:
        flags = ds["stable"].values
        assert np.all(flags[undecided] == -2)
        assert "-2 undecided" in ds["stable"].attrs["flag_values"]
        assert "max_floquet_real_uncertainty" in ds
    assert "2 speeds undecided: 900, 1200 rpm" in res.output


def test_a_failed_check_leaves_the_point_solved_and_its_speed_undecided(
    monkeypatch, tmp_path: Path
) -> None:
    """The eigensolver fails at 900 rpm (injected): the steady state there stands, the point
    says why it was not checked, and the map calls that speed undecided (exit 1), not
    stable and not a crash."""
    from scipy.sparse.linalg import ArpackNoConvergence

    floquet_package = sys.modules[
        "rheolin.floquet"
    ]  # the package (rheolin.floquet is the function)

    def failing(real):
        def floquet(system, *args, **kwargs):
            if abs(system.omega * 30 / np.pi - 900.0) < 1e-6:
                raise ArpackNoConvergence("ARPACK error -1: No convergence", [], [])
            return real(system, *args, **kwargs)

        return floquet

    monkeypatch.setattr(solve_module, "floquet", failing(solve_module.floquet))
    monkeypatch.setattr(floquet_package, "floquet", failing(floquet_package.floquet))
    res, out = _sweep_band(tmp_path)
    assert res.exit_code == 1, res.output
    table = json.loads((out / "sweep.json").read_text())
    i = int(np.flatnonzero(np.isclose(table["speeds_rpm"], 900.0))[0])
    assert table["stable"][i] is None and table["stability"][i] == "not checked"
    with xr.open_dataset(out / "sweep.nc") as ds:
        assert bool(ds["success"].values[i])
        assert "ArpackNoConvergence" in str(ds["message"].values[i]) or "ARPACK" in str(
            ds["message"].values[i]
        )
    assert "1 speed undecided: 900 rpm" in res.output
