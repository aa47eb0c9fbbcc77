"""``rheolin sweep --refine-peaks``: a run-up at 1000-rpm steps samples the resonance of a
damped rigid rotor (zeta = 0.05) with fewer than 5 speeds in its half-power band: the sweep
warns, and with --refine-peaks it adds speeds there until it is resolved, and the AF then
agrees with the half-power points of the closed-form response (brentq)."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

sys.path.insert(0, str(Path(__file__).parent))
from report_cases import run_cli

M, K, ZETA = 2.0, 1e6, 0.05
C = 2 * ZETA * math.sqrt(K * M)
ROTOR = f"""
[model]
name = "damped rigid rotor"
input_body = "r"

[[rigid_bodies]]
name = "r"
position = "0 0 0 m"
mass = "{M} kg"
inertia = ["0.01 kg*m^2", "0.01 kg*m^2", "0.02 kg*m^2"]
disks = [{{ node = 0, unbalance = "1e-4 kg*m" }}]

[[rigid_bodies.bearings]]
name = "b"
node = 0
components = ["ux", "uy", "uz", "phix", "phiy", "phiz"]
stiffness = ["{K} N/m", "{K} N/m", "{K} N/m", "1e4 N*m/rad", "1e4 N*m/rad", "1e4 N*m/rad"]
damping = ["{C} N*s/m", "{C} N*s/m", "{C} N*s/m", "1 N*m*s/rad", "1 N*m*s/rad", "1 N*m*s/rad"]
"""


def closed_form_af() -> float:
    """Half-power AF of |x| = U W^2 / |k - m W^2 + i c W| from its exact peak and crossings."""

    def x(w: float) -> float:
        return w**2 / abs(K - M * w**2 + 1j * C * w)

    wn = math.sqrt(K / M)
    ws = np.linspace(0.5 * wn, 1.5 * wn, 200001)
    peak = ws[int(np.argmax([x(w) for w in ws]))]
    level = x(peak) / math.sqrt(2)
    lo = brentq(lambda w: x(w) - level, 0.5 * wn, peak)
    hi = brentq(lambda w: x(w) - level, peak, 2.0 * wn)
    return peak / (hi - lo)


def test_coarse_peaks_are_said_and_refined(tmp_path):
    (tmp_path / "r.toml").write_text(ROTOR)
    base = ["sweep", "r.toml", "--speeds", "4000:10000:1000rpm", "--workers", "1",
            "--no-stability-map", "--no-plots"]  # fmt: skip
    res = run_cli(*base, "--out", "coarse", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    (peak,) = json.loads((tmp_path / "coarse" / "sweep.json").read_text())["resonances"]
    assert peak["resolved"] is False and peak["samples_in_band"] < 5
    assert "fewer than 5 speeds in their half-power band" in res.stderr
    res = run_cli(*base, "--out", "fine", "--refine-peaks", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert "refining resonance peaks (pass 1)" in res.stdout
    table = json.loads((tmp_path / "fine" / "sweep.json").read_text())
    (peak,) = table["resonances"]
    assert peak["resolved"] is True and peak["samples_in_band"] >= 5
    assert len(table["speeds_rpm"]) > 7
    assert peak["amplification_factor"] == pytest.approx(closed_form_af(), rel=0.03)
    wn_rpm = math.sqrt(K / M) * 30 / math.pi
    assert peak["speed_rpm"] == pytest.approx(wn_rpm / math.sqrt(1 - 2 * ZETA**2), rel=5e-3)
