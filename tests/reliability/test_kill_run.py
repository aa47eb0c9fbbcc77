"""``rheolin run`` killed with SIGKILL and SIGINT at random moments while it replaces an earlier
run's results: the output directory holds one run's files only (the earlier run's, or the
new run's), never a temporary file, and Ctrl-C exits 130 saying what was kept. (``sweep`` is
killed and resumed in tests/study/test_cli_study.py.)"""

from __future__ import annotations

import hashlib
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

sys.path.insert(0, str(Path(__file__).parents[1] / "study"))
from study_cases import BAND, ctrl_c_reaches_python

ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}


def _run(model: Path, out: Path, speed: str) -> list[str]:
    return [sys.executable, "-m", "rheolin.cli", "run", str(model), "--speed", speed,
            "--out", str(out)]  # fmt: skip


def _identity(out: Path) -> dict[str, object]:
    """What each file says about the run that wrote it."""
    ident: dict[str, object] = {}
    names = sorted(p.name for p in out.iterdir())
    for name in names:
        assert not name.startswith(".") and not name.endswith(".tmp"), names
    if (out / "summary.json").exists():
        ident["summary.json"] = round(json.loads((out / "summary.json").read_text())["speed"], 6)
    if (out / "results.nc").exists():
        with xr.open_dataset(out / "results.nc") as ds:
            ident["results.nc"] = round(float(ds.attrs["speed"]), 6)
    for name in names:
        if name.endswith(".png"):
            ident[name] = hashlib.sha256((out / name).read_bytes()).hexdigest()
    return ident


@pytest.fixture(scope="module")
def earlier(tmp_path_factory):
    """A finished run at 95 rad/s, and how long an uninterrupted run at 105 rad/s takes."""
    d = tmp_path_factory.mktemp("kill")
    (d / "band.toml").write_text(BAND)
    ref = d / "ref"
    res = subprocess.run(_run(d / "band.toml", ref, "95rad/s"), env=ENV, capture_output=True)
    assert res.returncode == 0, res.stderr
    t0 = time.monotonic()
    res = subprocess.run(_run(d / "band.toml", d / "new", "105rad/s"), env=ENV, capture_output=True)
    assert res.returncode == 1, res.stderr  # 105 rad/s is inside the unstable band
    return d, _identity(ref), _identity(d / "new"), time.monotonic() - t0


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGINT])
def test_killed_runs_leave_one_run_and_no_temporary_file(earlier, tmp_path, sig):
    d, old, new, seconds = earlier
    rng = np.random.default_rng(7 if sig == signal.SIGKILL else 8)
    out = tmp_path / "out"
    seen = set()
    for attempt in range(3 if sig == signal.SIGKILL else 2):
        if not out.exists() or _identity(out) != old:  # start each time from the earlier run
            subprocess.run(["rm", "-rf", str(out)], check=True)
            subprocess.run(["cp", "-r", str(d / "ref"), str(out)], check=True)
        # the first attempt holds its staged files for a second before moving them in, so
        # that the kill lands there whatever the machine's load (rheolin._pause)
        env = {**ENV, "RHEOLIN_TEST_PAUSE_STAGING": "1.0"} if attempt == 0 else ENV
        proc = subprocess.Popen(
            _run(d / "band.toml", out, "105rad/s"),
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            preexec_fn=ctrl_c_reaches_python,
        )
        if attempt == 0:
            # the first kill as soon as the new run stages its files, before it can move them
            # in: at least one kill must land there, whatever the machine's load
            t_end = time.monotonic() + 120
            while time.monotonic() < t_end and proc.poll() is None:
                if any(".partial-" in p.name for p in out.parent.iterdir()):
                    break
                time.sleep(0.002)
        else:
            time.sleep(rng.uniform(0.3, 1.1) * seconds)
        proc.send_signal(sig)
        _, stderr = proc.communicate(timeout=120)
        got = _identity(out)
        assert got in (old, new) or (set(got.items()) <= set(new.items())), (got, old, new)
        seen.add("old" if got == old else "new")
        assert "Traceback" not in stderr
        if sig == signal.SIGINT and proc.returncode == 130:
            # before the command names its output (loading), while it computes, or after
            # its files are moved in: each says what the directory holds
            if "are complete" in stderr:
                assert got == new, stderr
            else:
                assert "interrupted: nothing" in stderr and got == old, stderr
        for p in out.parent.iterdir():  # no staging directory left by a finished process
            assert ".partial-" not in p.name or sig == signal.SIGKILL, p.name
    assert "old" in seen  # at least one kill landed before the new files were moved in
