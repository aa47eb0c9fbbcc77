"""The HTML report's content: what it states equals the result files (verdicts, the
preloaded operating point, unstable range bounds sqrt(k_x/m) and sqrt(k_y/m), resonances
with their AF and API 617 margin), user text is escaped, a changed model file is said."""

from __future__ import annotations

import json
import math
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from rheolin.data import example_text
from rheolin.report import build_report, read_directory, write_report
from rheolin.results.api684 import required_margin

sys.path.insert(0, str(Path(__file__).parent))
from report_cases import run_cli, study_cases

BAND = study_cases().BAND


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    """``rheolin run`` of the preloaded example with --report."""
    d = tmp_path_factory.mktemp("pair")
    (d / "pair.toml").write_text(example_text("preloaded"))
    res = run_cli("run", str(d / "pair.toml"), "--out", str(d / "out"), "--report", cwd=d)
    assert res.returncode == 0, res.stderr
    return d


def test_run_report_states_the_verdict_and_the_operating_point(pair):
    text = (pair / "out" / "report.html").read_text(encoding="utf-8")
    s = json.loads((pair / "out" / "summary.json").read_text())
    assert f"Operating point at {s['speed_rpm']:.6g} rpm" in text
    # the verdict the files hold: this example's least damped motions (torsion of the shaft
    # ends, 22 kHz) are undamped, so its largest real part is round-off of either sign,
    # which reads stable (marginal)
    assert s["stability"] == "stable" and s["stability_decided"] is True
    assert abs(s["max_floquet_real"]) < 1e-9 and "backward error" in text
    assert f">{s['stability']}<" in text
    for name, b in s["operating_point"]["bearings"].items():
        assert f"bearing {name}</td><td>{b['load_N']:.4g} N" in text
    assert "Preloaded operating point" in text and 'class="drawing"' in text
    assert s["model_sha256"] in text and "matches the results" in text
    assert text.count('<div class="fig"') == 3
    markup = re.sub(r"<script[^>]*>.*?</script>", "", text, flags=re.S)  # the page, not its JS
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:|//)|url\(\s*["']?https?:""", markup)
    assert text.count("<script") == 2 + 3 + 1  # errors, plotly.js, 3 figures' data, loader


def test_a_report_of_rheolin_result_files_leaves_nothing_out(pair, tmp_path):
    left_out: list[str] = []
    write_report(pair / "out", path=tmp_path / "r.html", left_out=left_out)
    assert left_out == [] and (tmp_path / "r.html").is_file()


def test_a_changed_model_file_is_said(pair, tmp_path):
    changed = tmp_path / "pair.toml"
    changed.write_text((pair / "pair.toml").read_text().replace("60 N*m", "61 N*m"))
    d = read_directory(pair / "out", model=changed)
    assert any("has changed since these results were computed" in n for n in d.notes)
    assert "differs from the results" in build_report(d)


@pytest.fixture(scope="module")
def band(tmp_path_factory):
    """``rheolin sweep`` of the rigid rotor whose spring is stiffer in y, across its band,
    with a resonance: k_x / m = 1e4, k_y / m = 1.21e4 (100 and 110 rad/s)."""
    d = tmp_path_factory.mktemp("band")
    (d / "band.toml").write_text(
        BAND.replace('name = "rigid rotor', 'speed = "1000 rpm"\nname = "<b>rigid rotor')
    )
    res = run_cli("sweep", str(d / "band.toml"), "--speeds", "800:1200:20rpm", "--out",
                  str(d / "out"), "--workers", "1", "--report", cwd=d)  # fmt: skip
    assert res.returncode == 1, res.stderr  # unstable inside the band
    return d


def test_sweep_report_lists_the_band_with_its_bounds(band):
    text = (band / "out" / "report.html").read_text(encoding="utf-8")
    (r,) = json.loads((band / "out" / "sweep.json").read_text())["unstable_ranges"]
    assert r["lower_rpm"] == pytest.approx(100 * 30 / math.pi, rel=1e-5)
    assert r["upper_rpm"] == pytest.approx(110 * 30 / math.pi, rel=1e-5)
    assert f"<td>{r['lower_rpm']:.6g}</td><td>{r['upper_rpm']:.6g}</td>" in text
    assert "asymmetric shaft band" in text
    assert "&lt;b&gt;rigid rotor" in text and "<b>rigid rotor" not in text  # escaped


def test_resonance_margins_follow_api_617(band, tmp_path):
    """The separation margin of each resonance from the operating range given, and what API
    617 requires of its AF, as the report's table states them."""
    out = write_report(band / "out", operating_rpm=(1300.0, 1400.0), path=tmp_path / "r.html")
    text = out.read_text(encoding="utf-8")
    peaks = json.loads((band / "out" / "sweep.json").read_text())["resonances"]
    assert peaks, "the unbalance response peaks at the band's edges"
    for p in peaks:
        margin = (1300.0 - p["speed_rpm"]) / 1300.0
        required = required_margin(p["amplification_factor"], True)
        assert f"<td>{100 * margin:.1f} %</td><td>{100 * required:.1f} %</td>" in text
        assert isinstance(p["samples_in_band"], int) and p["resolved"] == (
            p["samples_in_band"] >= 5
        )


def test_report_command_refuses_a_directory_without_results(tmp_path):
    res = run_cli("report", str(tmp_path))
    assert res.returncode == 2 and "no result file" in res.stderr
    res = run_cli("report", str(tmp_path / "missing"))
    assert res.returncode == 2 and "not a directory" in res.stderr


def test_operating_range_option():
    from rheolin.cli.html_report import parse_operating

    assert parse_operating("2800:3200rpm") == (2800.0, 3200.0)
    lo, hi = parse_operating("47:53Hz")
    assert (lo, hi) == pytest.approx((2820.0, 3180.0))
    assert np.isclose(parse_operating("314.159265rad/s")[0], 3000.0, rtol=1e-8)


def test_parameter_study_report_lists_each_band_with_its_parameter(tmp_path):
    """k_y = 1.21e4 and 1.44e4 N/m: bands from sqrt(k_x/m) = 100 rad/s to sqrt(k_y/m) = 110
    and 120 rad/s, each listed with its parameter value."""
    (tmp_path / "band.toml").write_text(BAND)
    res = run_cli("sweep", "band.toml", "--speeds", "900:1200:50rpm", "--out", "study",
                  "--vary", "bearings.spring.stiffness[1]=1.21e4,1.44e4 N/m", "--workers", "1",
                  "--report", cwd=tmp_path)  # fmt: skip
    assert res.returncode == 1, res.stderr
    text = (tmp_path / "study" / "report.html").read_text(encoding="utf-8")
    for ky, upper in ((12100.0, 110.0), (14400.0, 120.0)):
        row = f"<td>{upper * 30 / math.pi:.6g}</td>"
        assert row in text and f"bearings.spring.stiffness[1] = {ky}" in text
