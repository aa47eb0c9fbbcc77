"""The CLI: results reopened with xarray and compared with the Python API; broken files refused
with exit status 2 and a message naming the field; atomic writes.

Commands run in this process (tests/run_cli.py), the run of the shared fixture through
``python -m rheolin.cli``."""

from __future__ import annotations

import json
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from rheolin.data import example_text
from rheolin.io import atomic_write, parse_model
from rheolin.results import complex_values, solve_point
from rheolin.results.units import missing_units
from rheolin.study import MAP_PRECISION

sys.path.insert(0, str(Path(__file__).parents[1] / "io"))
sys.path.insert(0, str(Path(__file__).parents[1] / "study"))
from study_cases import BAND
from test_loader import SMALL, _broken

from run_cli import cli, cli_process


@pytest.fixture(autouse=True)
def _allow_underflow():
    with np.errstate(under="ignore"):
        yield


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("run")
    (d / "model.toml").write_text(SMALL)
    res = cli_process(  # the entry point itself: a real process writes the run's files
        "run",
        str(d / "model.toml"),
        "--speed",
        "2000rpm",
        "--out",
        str(d / "out"),
        "--json",
        "--stability",
        "off",
        "--harmonics",
        "3",
    )
    return d, res


def test_run_results_reopen_with_xarray_and_match_the_python_api(small_run):
    d, res = small_run
    assert res.returncode == 0, res.stderr
    summary = json.loads(res.stdout)
    assert summary["success"] == 1 and summary["stability"] == "not checked"
    assert json.loads((d / "out" / "summary.json").read_text())["residual"] == summary["residual"]
    ds = xr.open_dataset(d / "out" / "results.nc")
    assert missing_units(ds) == []  # docs/results-schema.md, Units
    loaded = parse_model(SMALL)
    p = solve_point(loaded.model, 2000 * np.pi / 30, order=3, stability=False)
    ref = p.solution
    assert ds.attrs["model_sha256"] == loaded.sha256
    assert ds.attrs["method"] == ref.method and ds.attrs["iterations"] == ref.iterations
    assert np.isclose(ds.attrs["residual"], ref.residual, rtol=1e-3, atol=1e-14)
    assert ds["frequency"].attrs["units"] == "Hz"
    assert np.allclose(ds["order"], ds["harmonic"] * float(p.assembled.base_ratio))
    q = complex_values(ds["displacement"].sel(node="b:1", component=["ux", "uy"]))
    dofs = p.assembled.dofs("b", 1)[:2]
    expected = np.array([ref.harmonic(int(n))[dofs] for n in ds["harmonic"].values])
    assert np.allclose(q.values, expected, rtol=1e-9, atol=1e-9 * np.abs(expected).max())
    from rheolin.results.outputs import bearing_forces, transmission_errors

    F = complex_values(ds["bearing_force"].sel(bearing="a2"))
    rows = bearing_forces(ref, p.assembled, "a2")
    assert np.allclose(F.values, [r.value for r in rows], atol=1e-9 * abs(F.values).max())
    E = complex_values(ds["dte"].sel(mesh="mesh"))
    rows = transmission_errors(ref, p.assembled, "mesh")
    assert np.allclose(E.values, [r.value[0] for r in rows], atol=1e-9 * abs(E.values).max())


def test_a_cut_off_below_the_mesh_load_is_reported(small_run, tmp_path):
    """The transmission error loads the 20-tooth mesh at order 20: ``--max-order 10`` leaves it
    out (the DTE disappears), and the run says so on stderr and in summary.json."""
    d, res = small_run
    assert json.loads(res.stdout)["warnings"] == []
    cut = cli(
        "run",
        str(d / "model.toml"),
        "--out",
        str(tmp_path / "cut"),
        "--max-order",
        "10",
        "--stability",
        "off",
        "--no-plots",
    )
    assert cut.returncode == 0, cut.stderr
    assert "warning:" in cut.stderr and "orders 20 of the input speed" in " ".join(
        cut.stderr.split()
    )
    notes = json.loads((tmp_path / "cut" / "summary.json").read_text())["warnings"]
    assert len(notes) == 1 and "max_order=10 leaves out 1 of 3 load harmonics" in notes[0]
    full = xr.open_dataset(d / "out" / "results.nc")
    assert (
        20 in full["order"].values
        and 20 not in xr.open_dataset(tmp_path / "cut" / "results.nc")["order"].values
    )
    assert float(np.abs(complex_values(full["dte"].sel(order=20))).max()) > 1e-7  # ~ 2 um TE


def test_run_with_the_transient_method_matches_the_frequency_domain(small_run, tmp_path):
    """``--method transient`` integrates from rest with BDF to the periodic steady state; its
    harmonics match the frequency-domain run of the same file."""
    d, _ = small_run
    res = cli(
        "run",
        str(d / "model.toml"),
        "--speed",
        "2000rpm",
        "--method",
        "transient",
        "--out",
        str(tmp_path / "tr"),
        "--json",
        "--stability",
        "off",
        "--harmonics",
        "3",
        "--no-plots",
    )
    assert res.returncode == 0, res.stderr
    summary = json.loads(res.stdout)
    assert summary["success"] == 1 and summary["method"] == "transient", summary["message"]
    assert "periodic steady state" in summary["message"] and summary["iterations"] >= 2
    fd = complex_values(xr.open_dataset(d / "out" / "results.nc")["displacement"])
    tr = complex_values(xr.open_dataset(tmp_path / "tr" / "results.nc")["displacement"])
    assert fd.shape == tr.shape
    err = float(np.abs(tr - fd).max() / np.abs(fd).max())
    assert err < 1e-6, err  # period_tol is 1e-6 at the default rtol 1e-8; measured 2.6e-9


def test_run_writes_plots_and_no_temporary_files(small_run):
    d, _ = small_run
    names = sorted(p.name for p in (d / "out").iterdir())
    expected = ["bearing_forces.png", "convergence.png", "orbits.png", "results.nc"]
    assert names == sorted([*expected, "spectrum.png", "summary.json"])
    for name in names:
        if name.endswith(".png"):
            assert (d / "out" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


BROKEN = [
    (_broken('outer_diameter = "30 mm"', 'outer_diametr = "30 mm"'), "shafts[0].outer_diametr"),
    (_broken('stiffness = "3e8 N/m"', 'stiffness = "3e8 N*m"'), "meshes[0].stiffness"),
    (_broken('name = "a2"\nnode = 2', 'name = "a2"\nnode = 9'), "shafts[0].bearings[1].node"),
    (_broken("gear_teeth = 40", "gear_teeth = 45"), "meshes[0].gear_teeth"),
    (_broken('gear_body = "b"', 'gear_body = "nope"'), "meshes[0].gear_body"),
    ("[model\nspeed = 1", "not valid TOML"),
]


@pytest.mark.parametrize(("text", "field"), BROKEN, ids=[b[1] for b in BROKEN])
def test_broken_files_exit_2_naming_the_field(tmp_path, text, field):
    path = tmp_path / "broken.toml"
    path.write_text(text)
    command = ["run", str(path), "--out", str(tmp_path / "o")] if "TOML" in field else []
    res = cli(*(command or ["validate", str(path)]))
    assert res.returncode == 2, (res.stdout, res.stderr)
    assert field in res.stderr and "Traceback" not in res.stderr
    assert not (tmp_path / "o").exists()


def test_example_validate_and_bad_options(tmp_path):
    res = cli("example", "gearbox")
    assert res.returncode == 0 and res.stdout == example_text("gearbox")
    (tmp_path / "g.toml").write_text(res.stdout)
    res = cli("validate", str(tmp_path / "g.toml"))
    assert res.returncode == 0 and "valid" in res.stdout and "1/4757" in res.stdout
    assert cli("example", "nope").returncode == 2
    bad = [("--method", "nope"), ("--speed", "3000 kg"), ("--harmonics", "-1")]
    for opt, value in bad:
        res = cli("run", str(tmp_path / "g.toml"), opt, value, "--out", str(tmp_path / "x"))
        assert res.returncode == 2 and opt in res.stderr, (opt, res.stderr)
    for command in ("run", "sweep"):
        res = cli(command, "--help")
        assert res.returncode == 0 and "Usage" in res.stdout
    assert "Exit codes" in cli("--help").stdout


def test_version_option_and_command_print_the_project_version():
    """``rheolin --version`` and ``rheolin version`` print pyproject.toml's version, exit 0."""
    project = tomllib.loads((Path(__file__).parents[2] / "pyproject.toml").read_text())
    expected = project["project"]["version"]
    res = cli("--version")
    assert (res.returncode, res.stdout, res.stderr) == (0, f"rheolin {expected}\n", "")
    res = cli("version")
    assert (res.returncode, res.stdout) == (0, f"{expected}\n")
    res = cli("--version", "run", "no-such-file.toml")  # eager: the command is not run
    assert (res.returncode, res.stdout, res.stderr) == (0, f"rheolin {expected}\n", "")
    assert "--version" in cli("--help").stdout


def test_sweep_writes_results_over_speed(tmp_path):
    res = cli("example", "rotor")
    (tmp_path / "r.toml").write_text(res.stdout)
    res = cli(
        "sweep",
        str(tmp_path / "r.toml"),
        "--speeds",
        "1000:3000:1000rpm",
        "--out",
        str(tmp_path / "s"),
        "--stability",
        "off",
        "--no-stability-map",
    )
    assert res.returncode == 0, res.stderr
    ds = xr.open_dataset(tmp_path / "s" / "sweep.nc")
    assert missing_units(ds) == []
    assert np.allclose(ds["speed_rpm"], [1000, 2000, 3000])
    assert ds["response"].dims == ("speed", "harmonic", "node")
    assert (ds["success"] == 1).all() and (ds["stable"] == -1).all()
    m = parse_model((tmp_path / "r.toml").read_text()).model
    ref = solve_point(m, 2000 * np.pi / 30, order=4, stability=False).solution
    amp = 2 * np.abs(ref.harmonic(1)[6:8])  # node rotor:1, ux and uy
    got = float(ds["response"].sel(speed=2000 * np.pi / 30, harmonic=1, node="rotor:1"))
    assert np.isclose(got, np.hypot(*amp), rtol=1e-6)
    table = json.loads((tmp_path / "s" / "sweep.json").read_text())
    assert table["stable"] == [None, None, None]
    assert (tmp_path / "s" / "sweep.png").stat().st_size > 10000


OVERHUNG = """
[model]
name = "overhung disk"
input_body = "rotor"

[[shafts]]
name = "rotor"
positions = "0 250 mm"
outer_diameter = "30 mm"
elastic_modulus = "210 GPa"
poisson_ratio = 0.3
density = "0 kg/m^3"

[[shafts.disks]]
node = 1
mass = "8 kg"
inertia = ["0.04 kg*m^2", "0.04 kg*m^2", "0.07 kg*m^2"]

[[shafts.bearings]]
name = "clamp"
node = 0
components = "all"
stiffness = ["1e12 N/m", "1e12 N/m", "1e12 N/m", "1e12 N*m/rad", "1e12 N*m/rad", "1e12 N*m/rad"]
"""


def test_campbell_checks_stability_on_workers(tmp_path):
    """The rigid rotor on a spring fixed in its own axes (tests/study/study_cases.py): unstable
    exactly between sqrt(k_x / m) = 100 and sqrt(k_y / m) = 110 rad/s. With ``--workers 2``
    the check runs on two worker processes while the diagram is drawn: the range's bounds in
    stability_map.nc and on the console, exit 1 (an unstable range)."""
    (tmp_path / "band.toml").write_text(BAND)
    out = tmp_path / "c"
    res = cli("campbell", str(tmp_path / "band.toml"), "--speeds", "61:150:4rad/s",
              "--workers", "2", "--out", str(out))  # fmt: skip
    assert res.returncode == 1, res.stdout + res.stderr
    ds = xr.open_dataset(out / "stability_map.nc")
    # the bounds to the map's precision (MAP_PRECISION) around the closed form
    assert float(ds["range_lower"][0]) == pytest.approx(100.0, rel=MAP_PRECISION)
    assert float(ds["range_upper"][0]) == pytest.approx(110.0, rel=MAP_PRECISION)
    assert ds.sizes["speed"] == 23
    assert "unstable 954.93" in res.stdout and "1050.42" in res.stdout
    assert (out / "campbell.nc").exists() and (out / "campbell.png").exists()
    bad = cli("campbell", str(tmp_path / "band.toml"), "--speeds", "60:150:10rad/s",
              "--workers", "0", "--out", str(tmp_path / "d"))  # fmt: skip
    assert bad.returncode == 2 and "--workers" in bad.stderr


def test_campbell_writes_the_gyroscopic_split_and_critical_speeds(tmp_path):
    """The overhung disk of tests/stability/test_campbell.py written as a model file: the
    forward/backward frequencies in campbell.nc solve the closed-form whirl quartic."""
    sys.path.insert(0, str(Path(__file__).parents[1] / "stability"))
    from test_campbell import JP, JT, M, _tip_stiffness, _whirl_frequencies

    (tmp_path / "o.toml").write_text(OVERHUNG)
    res = cli(
        "campbell",
        str(tmp_path / "o.toml"),
        "--speeds",
        "400:3000:25rad/s",
        "--out",
        str(tmp_path / "c"),
    )
    assert res.returncode == 0, res.stderr
    ds = xr.open_dataset(tmp_path / "c" / "campbell.nc")
    assert missing_units(ds) == []
    assert np.allclose(ds["speed"], np.arange(400, 3001, 25))
    for W in (500.0, 3000.0):
        row = ds.sel(speed=W)
        for sign, kind in ((+1, "forward"), (-1, "backward")):
            got = 2 * np.pi * np.sort(row["frequency"].values[row["whirl"].values == kind])
            np.testing.assert_allclose(got, _whirl_frequencies(W, sign), rtol=1e-8)
    # the forward 1x critical speed: (k11 - m W^2)(k22 - (J_t - J_p) W^2) = k12^2
    (k11, k12), (_, k22) = _tip_stiffness()
    x = np.roots(np.polysub(np.polymul([-M, k11], [JP - JT, k22]), [k12**2]))
    ref = np.sqrt(x.real[(x.real > 0) & (np.abs(x.imag) < 1e-9)]).min()
    fwd = (ds["critical_order"] == "1x rotor") & (ds["critical_whirl"] == "forward")
    assert float(ds["critical_speed"][fwd].min()) == pytest.approx(ref, rel=2e-3)
    assert ds["frequency"].attrs["units"] == "Hz" and ds["critical_speed"].attrs["units"] == "rad/s"
    assert "critical speeds" in res.stdout
    assert (tmp_path / "c" / "campbell.png").stat().st_size > 10000


RIGID_BAND = BAND  # tests/study/study_cases.py


def test_sweep_stability_map_finds_the_asymmetric_band(tmp_path):
    """A spring fixed in the rotor's axes with k_x != k_y: unstable exactly between
    sqrt(k_x/m) = 100 and sqrt(k_y/m) = 110 rad/s (no damping in the plane)."""
    (tmp_path / "b.toml").write_text(RIGID_BAND)
    res = cli(
        "sweep",
        str(tmp_path / "b.toml"),
        "--speeds",
        "900:1100:50rpm",
        "--out",
        str(tmp_path / "s"),
        "--stability",
        "off",
    )
    # the forced response exists at every speed, but the map finds the band: an unstable
    # range is a failure of the sweep (exit 1), never "0 unstable" (issue 18)
    assert res.returncode == 1, res.stderr
    assert "stability (from the map): 2 unstable" in res.stdout
    table = json.loads((tmp_path / "s" / "sweep.json").read_text())
    (band,) = table["unstable_ranges"]
    # bounds refined by Brent's method to the sweep's stated precision
    assert band["lower_rpm"] == pytest.approx(100 * 30 / np.pi, rel=MAP_PRECISION)
    assert band["upper_rpm"] == pytest.approx(110 * 30 / np.pi, rel=MAP_PRECISION)
    assert band["mechanism"] == "asymmetric shaft band" and not band["open_above"]
    smap = xr.open_dataset(tmp_path / "s" / "stability_map.nc")
    assert missing_units(smap) == []
    inside = (smap["speed"] > 100) & (smap["speed"] < 110)
    assert (smap["stable"] == ~inside).all()
    assert (tmp_path / "s" / "stability_map.png").stat().st_size > 10000


def test_atomic_write_leaves_old_file_on_interruption(tmp_path):
    target = tmp_path / "results.nc"
    target.write_text("old")
    with pytest.raises(KeyboardInterrupt), atomic_write(target) as tmp:
        tmp.write_text("half")
        raise KeyboardInterrupt
    assert target.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["results.nc"]
