"""``rheolin frf``: the peaks it prints sit at the damped natural frequencies
of the model's modes (an eigenvalue solve: a different computation from the FRF's linear
solves), the files reopen, and bad options exit 2 naming the option."""

from __future__ import annotations

import functools
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import run_cli
from rheolin.io import parse_model
from rheolin.results import complex_values
from rheolin.results.units import missing_units
from rheolin.stability import averaged_modes

cli = functools.partial(run_cli.cli, columns=160)

ROTOR = """
[model]
input_body = "rotor"

[[shafts]]
name = "rotor"
positions = "0 150 300 mm"
outer_diameter = "40 mm"
material = "steel"
disks = [{ node = 1, outer_diameter = "250 mm", width = "30 mm" }]

[[shafts.bearings]]
name = "left"
node = 0
components = ["ux", "uy", "uz", "phiz"]
stiffness = ["2e7 N/m", "2e7 N/m", "1e8 N/m", "1e4 N*m/rad"]
damping = ["300 N*s/m", "300 N*s/m", "300 N*s/m", "1 N*m*s/rad"]

[[shafts.bearings]]
name = "right"
node = 2
stiffness = "2e7 N/m"
damping = "300 N*s/m"
"""


def test_frf_peaks_at_the_damped_natural_frequencies(tmp_path: Path) -> None:
    (tmp_path / "rotor.toml").write_text(ROTOR)
    step = 0.05  # Hz
    res = cli("frf", str(tmp_path / "rotor.toml"), "--speed", "3000rpm",
              "--frequencies", f"150:450:{step}Hz", "--input", "rotor:1:ux",
              "--out", str(tmp_path / "out"))  # fmt: skip
    assert res.returncode == 0, res.stderr
    assert "stable" in res.stdout
    rows = re.findall(
        r"rotor:1:ux\s*│\s*rotor:1:ux\s*│\s*([0-9.]+)\s*│[^│]*│[^│]*│\s*([0-9.]+)", res.stdout
    )
    model = parse_model(ROTOR).model
    lam = averaged_modes(model.assemble(3000 * np.pi / 30).system).eigenvalues
    fd = lam.imag / (2 * np.pi)
    assert rows
    for f_text, af_text in rows:
        # each printed peak is a mode's damped frequency (within the grid step), and its
        # half-power amplification factor is that mode's 1 / (2 zeta) = |lambda| / (2 |Re|)
        i = int(np.argmin(np.abs(fd - float(f_text))))
        assert abs(fd[i] - float(f_text)) < step, (f_text, fd)
        assert float(af_text) == pytest.approx(abs(lam[i]) / (2 * abs(lam[i].real)), rel=0.03)
    peaks = [float(f) for f, _ in rows]
    ds = xr.open_dataset(tmp_path / "out" / "frf.nc")
    assert missing_units(ds) == [] and ds["receptance"].attrs["units"] == "m/N"
    H = complex_values(ds["receptance"]).sel(output="rotor:1:ux", input="rotor:1:ux").values
    top = float(ds["frequency"].values[int(np.argmax(np.abs(H)))])
    assert np.min(np.abs(np.array(peaks) - top)) < 2 * step  # the file holds what was printed
    assert np.all(np.isfinite(H)) and ds.attrs["stable"] == 1
    assert (tmp_path / "out" / "bode.png").stat().st_size > 10_000


def test_frf_bad_options_exit_2_naming_the_option(tmp_path: Path) -> None:
    (tmp_path / "rotor.toml").write_text(ROTOR)
    base = ["frf", str(tmp_path / "rotor.toml"), "--speed", "3000rpm"]
    res = cli(*base, "--frequencies", "1:100:1Hz", "--input", "rotor:9:ux")
    assert res.returncode == 2 and "--input" in res.stderr and "no node 9" in res.stderr
    res = cli(*base, "--frequencies", "100:1:1Hz", "--input", "rotor:1:ux")
    assert res.returncode == 2 and "--frequencies" in res.stderr
    res = cli(*base, "--frequencies", "1:100:1Hz", "--input", "rotor:1:ux", "--output", "x:1:ux")
    assert res.returncode == 2 and "--output" in res.stderr and "no body 'x'" in res.stderr
