"""``rheolin sweep`` as a study in a subprocess: killed with SIGKILL at random moments and
resumed (every file readable after every kill, the final results equal to an uninterrupted
run's, no point lost or duplicated); Ctrl-C; refusals with exit code 2."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from rheolin.study.chunks import floquet_results, read_chunk

sys.path.insert(0, str(Path(__file__).parent))
from study_cases import BAND, ctrl_c_reaches_python

from run_cli import ENV, cli

POINTS = 51
SWEEP = ["--speeds", "850:1250:8rpm", "--chunk-size", "3"]  # 51 points, the band inside


def command(model: Path, out: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "rheolin.cli", "sweep", str(model), "--out", str(out), *extra]


@pytest.fixture(scope="module")
def band(band_file):
    return band_file


@pytest.fixture(scope="module")
def uninterrupted(band, tmp_path_factory):
    out = tmp_path_factory.mktemp("whole")
    res = cli("sweep", str(band), "--out", str(out), *SWEEP, "--workers", "1")
    assert res.returncode == 1, res.stderr  # the band's points are unstable
    return out


def _check_readable(out: Path) -> set[int]:
    """Open every file a killed run left; return the points in the chunk files."""
    if not out.exists():  # killed before it made the directory
        return set()
    names = {p.name for p in out.iterdir()}
    assert names <= {".rheolin.lock", "checkpoint"} | {n for n in names if n.endswith(".tmp")}
    points: list[int] = []
    ckpt = out / "checkpoint"
    if not ckpt.exists():
        return set()
    for p in ckpt.iterdir():
        if p.name == "manifest.json":
            assert json.loads(p.read_text())["points"] == POINTS
        elif p.name.startswith("chunk-"):
            ds = read_chunk(p)
            assert set(floquet_results(ds)) == set(ds["point"].values.tolist())
            points += ds["point"].values.tolist()
        else:  # only the temporary files of a write that the kill interrupted
            assert p.name.startswith(".") and p.name.endswith(".tmp"), p.name
    assert len(points) == len(set(points))  # no point twice
    return set(points)


def test_sigkill_at_random_moments_then_resume(band, uninterrupted, tmp_path):
    rng = np.random.default_rng(2024)
    out = tmp_path / "out"
    done: set[int] = set()
    killed = 0
    for round_ in range(4):
        workers = "2" if round_ % 2 else "1"  # serial and on a local Dask cluster
        proc = subprocess.Popen(
            command(band, out, *SWEEP, "--workers", workers),
            env=ENV,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        # wait for a random number of new chunk files (or a random early moment), then a
        # random fraction of a chunk more: kills land in start-up, solves and writes
        # (9 chunks in all: the continuation blocks hold 6 speeds; at most 2 per round
        # leave work for every round)
        wanted = int(rng.integers(0, 3))
        start = len(list((out / "checkpoint").glob("chunk-*.nc"))) if out.exists() else 0
        deadline = time.monotonic() + 120
        while proc.poll() is None and time.monotonic() < deadline:
            now = len(list((out / "checkpoint").glob("chunk-*.nc"))) if out.exists() else 0
            if now - start >= wanted:
                break
            time.sleep(0.01)
        time.sleep(float(rng.uniform(0.0, 0.4)))
        if proc.poll() is None:
            proc.send_signal(signal.SIGKILL)
            killed += 1
        proc.wait()
        points = _check_readable(out)
        assert points >= done  # finished points are never lost
        done = points
    assert killed >= 3, "the kills should interrupt runs"
    final = subprocess.run(
        command(band, out, *SWEEP), env=ENV, capture_output=True, text=True, timeout=600
    )
    assert final.returncode == 1, final.stderr  # unstable points, as uninterrupted
    assert f"resumed: {len(done)} of {POINTS} points already done" in final.stderr
    assert not [p for p in out.rglob("*.tmp")]  # stale temporary files removed
    assert _check_readable_final(out) == set(range(POINTS))
    for name in ("sweep.nc", "stability_map.nc"):
        a = xr.open_dataset(out / name).drop_vars("seconds", errors="ignore")
        b = xr.open_dataset(uninterrupted / name).drop_vars("seconds", errors="ignore")
        xr.testing.assert_identical(a, b)
    a = json.loads((out / "sweep.json").read_text())
    b = json.loads((uninterrupted / "sweep.json").read_text())
    assert a["unstable_ranges"] == b["unstable_ranges"] and len(a["unstable_ranges"]) == 1
    assert a["points"]["resumed"] == len(done) and a["points"]["total"] == POINTS


def _check_readable_final(out: Path) -> set[int]:
    points = [
        p for c in (out / "checkpoint").glob("chunk-*.nc") for p in read_chunk(c)["point"].values
    ]
    assert len(points) == len(set(points))
    return set(int(p) for p in points)


def test_ctrl_c_keeps_the_finished_chunks(band, uninterrupted, tmp_path):
    """SIGINT to the whole process group, as a terminal's Ctrl-C (the Dask workers too)."""
    out = tmp_path / "out"
    proc = subprocess.Popen(
        command(band, out, *SWEEP, "--workers", "2"),
        env={**ENV, "RHEOLIN_TEST_PAUSE_CHUNK": "0.1"},  # the study outlasts the watcher
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        preexec_fn=ctrl_c_reaches_python,
    )
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(list(out.glob("checkpoint/chunk-*.nc"))) < 3:
        time.sleep(0.01)
    os.killpg(proc.pid, signal.SIGINT)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr
    assert "interrupted:" in stderr and "run the same command again to resume" in stderr
    assert "Traceback" not in stderr
    kept = _check_readable(out)
    assert len(kept) >= 9  # the three chunks seen before the interrupt
    final = cli("sweep", str(band), "--out", str(out), *SWEEP, "--workers", "1")
    assert f"resumed: {len(kept)} of {POINTS}" in final.stderr
    a = xr.open_dataset(out / "sweep.nc").drop_vars("seconds")
    b = xr.open_dataset(uninterrupted / "sweep.nc").drop_vars("seconds")
    xr.testing.assert_identical(a, b)


@pytest.mark.parametrize(
    ("vary", "field"),
    [
        ("bearings.nope.stiffness=1e4:2e4:3 N/m", "bearings.nope.stiffness"),
        ("bearings.spring.stiffness[1]=1e4:2e4:3 kg", "rigid_bodies[0].bearings[0].stiffness[1]"),
        ("bearings.spring.stiffness[1]=2e4:1e4:3 N/m", "bearings.spring.stiffness[1]"),
        ("bearings.spring.stiffness[1]=1e4:2e4:0 N/m", "bearings.spring.stiffness[1]"),
    ],
)
def test_bad_vary_exits_2_with_one_line_naming_the_field(band, tmp_path, vary, field):
    res = cli(
        "sweep",
        str(band),
        "--speeds",
        "900:1000:50rpm",
        "--out",
        str(tmp_path / "o"),
        "--vary",
        vary,
    )
    assert res.returncode == 2, res.stderr
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: --vary") and field in lines[0], lines
    assert not (tmp_path / "o").exists()


def test_another_study_in_the_directory_is_refused_then_replaced(band, tmp_path):
    out = tmp_path / "out"
    args = ["--speeds", "900:1000:50rpm", "--no-stability-map", "--workers", "1"]
    assert cli("sweep", str(band), "--out", str(out), *args).returncode == 1
    changed = tmp_path / "changed.toml"
    changed.write_text(BAND.replace('"1.21e4 N/m"', '"1.44e4 N/m"'))
    res = cli("sweep", str(changed), "--out", str(out), *args)
    assert res.returncode == 2 and "the model file changed" in res.stderr
    res = cli("sweep", str(changed), "--out", str(out), *args, "--overwrite")
    assert res.returncode == 1 and "resumed" not in res.stderr
    assert json.loads((out / "sweep.json").read_text())["points"]["computed"] == 3
    res = cli(
        "sweep",
        str(band),
        "--out",
        str(out),
        "--speeds",
        "900:1000:50rpm",
        "--workers",
        "1",
        "--overwrite",
        "--vary",
        "bearings.spring.stiffness[1]=1.2e4,1.3e4 N/m",
    )
    assert res.returncode == 1, res.stderr
    names = sorted(p.name for p in out.iterdir())
    # the earlier run's sweep.png is gone: the parameter study draws one plot per parameter
    assert names == [
        ".rheolin.lock",
        "checkpoint",
        "stability_map.nc",
        "sweep.json",
        "sweep.nc",
        "vary_bearings.spring.stiffness_1_.png",
    ]


ISO = BAND.replace(
    'stiffness = ["1e4 N/m", "1.21e4 N/m"]\ndamping = ["0 N*s/m", "0 N*s/m"]\nframe = "r"',
    'stiffness = ["1e4 N/m", "1e4 N/m"]\ndamping = ["10 N*s/m", "10 N*s/m"]',
)


def test_sweep_reports_resonances_with_their_amplification_factor(tmp_path):
    """The rigid rotor on an isotropic spring, zeta = 0.05, w_n = 100 rad/s: one resonance,
    its peak and half-power amplification factor as the closed form of the unbalance response
    ``e W^2 / |w_n^2 - W^2 + 2 i zeta w_n W|`` (root finding on the analytic curve)."""
    from scipy.optimize import brentq

    assert ISO != BAND
    (tmp_path / "iso.toml").write_text(ISO)
    out = tmp_path / "s"
    res = cli("sweep", str(tmp_path / "iso.toml"), "--speeds", "600:1400:4rpm",
              "--stability", "off", "--no-stability-map", "--workers", "1", "--no-plots",
              "--out", str(out))  # fmt: skip
    assert res.returncode == 0, res.stdout + res.stderr
    assert "resonances (half-power amplification factor, API 684): r (" in res.stdout
    (peak,) = json.loads((out / "sweep.json").read_text())["resonances"]
    zeta, wn = 0.05, 100.0
    x = lambda w: w**2 / abs(wn**2 - w**2 + 2j * zeta * wn * w)  # noqa: E731
    wp = wn / np.sqrt(1 - 2 * zeta**2)
    lo = brentq(lambda w: x(w) - x(wp) / np.sqrt(2), 50.0, wp)
    hi = brentq(lambda w: x(w) - x(wp) / np.sqrt(2), wp, 200.0)
    assert abs(peak["speed_rpm"] * np.pi / 30 / wp - 1) < 1e-3
    assert abs(peak["amplification_factor"] / (wp / (hi - lo)) - 1) < 5e-3
    # the study's response is hypot(|x_n|, |y_n|) x 2 per harmonic: sqrt(2) R on a circular
    # orbit of radius R = e x(W), e = 1e-6 kg m / 1 kg
    assert abs(peak["amplitude_m"] / (np.sqrt(2) * 1e-6 * x(wp)) - 1) < 1e-3
