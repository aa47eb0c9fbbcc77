"""The report in a real browser: headless Chromium with the network cut off loads it without
a script error and without asking for any resource, draws every figure, and its screenshot
shows the figures' traces, which a screenshot of the same page with JavaScript off lacks.

Chromium comes from the system packages (Debian's ``chromium``; ``.ci/run`` installs it).
Without it the test is skipped with a warning that says so."""

from __future__ import annotations

import re
import shutil
import subprocess
import warnings
from pathlib import Path

import numpy as np
import pytest

from rheolin.data import example_text
from rheolin.io import read_model
from rheolin.report import write_report
from rheolin.results import point_dataset, solve_point, summarize, write_dataset, write_summary

CHROMIUM = next((p for p in map(shutil.which, ("chromium", "chromium-browser")) if p), None)
FLAGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--host-resolver-rules=MAP * ~NOTFOUND", "--virtual-time-budget=20000", "--hide-scrollbars",
]  # fmt: skip
#: The first traces' colours: the spectrum's (#1f77b4) and plotly's first (#636efa), RGB.
TRACES = np.array([[31, 119, 180], [99, 110, 250]])


@pytest.fixture(scope="module")
def report(tmp_path_factory) -> Path:
    """The rotor example at 3000 rpm: results, summary and report written as ``run`` does."""
    d = tmp_path_factory.mktemp("rotor")
    model = d / "rotor.toml"
    model.write_text(example_text("rotor"))
    lm = read_model(model)
    ds = point_dataset(solve_point(lm.model, 100 * np.pi, stability=True), model_sha256=lm.sha256)
    write_dataset(ds, d / "results.nc")
    summary = summarize(ds)
    summary["model_file"] = str(model)
    write_summary(summary, d / "summary.json")
    return write_report(d)


def _chromium(page: Path, tmp: Path, *args: str) -> subprocess.CompletedProcess:
    if CHROMIUM is None:
        message = (
            "Chromium is not installed: the report was NOT checked in a browser "
            "(apt-get install chromium; .ci/run installs it)"
        )
        warnings.warn(message, stacklevel=2)
        pytest.skip(message)
    profile = tmp / f"profile{len(list(tmp.iterdir()))}"
    profile.mkdir()
    cmd = [CHROMIUM, *FLAGS, f"--user-data-dir={profile}", *args, page.as_uri()]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120)


def _pixels(png: Path) -> tuple[int, int]:
    """Pixels of the traces' colours, and pixels that are drawn at all (far from white)."""
    from PIL import Image

    rgb = np.asarray(Image.open(png).convert("RGB"), dtype=int)
    traces = sum(int((np.abs(rgb - c).max(axis=2) < 25).sum()) for c in TRACES)
    return traces, int(((255 - rgb).max(axis=2) > 60).sum())


def test_report_opens_offline_and_draws_every_figure(report, tmp_path):
    res = _chromium(report, tmp_path, "--dump-dom")
    body = re.search(r"<body([^>]*)>", res.stdout)
    assert body, res.stderr[-2000:]
    attrs = dict(re.findall(r'data-([a-z]+)="([^"]*)"', body.group(1)))
    figures = report.read_text(encoding="utf-8").count('<div class="fig"')
    assert figures == 3
    assert attrs.get("errors") == "", attrs
    assert attrs.get("requests") == ""  # nothing asked of the network, nothing loaded
    assert int(attrs["figures"]) == figures and int(attrs["rendered"]) == figures
    assert res.stdout.count('class="main-svg"') >= figures


def test_screenshot_shows_the_figures_that_javascript_draws(report, tmp_path):
    """The same page without its scripts has no plotly figure: the trace colour's pixels in
    the first 1800 px of the page come from the drawn figures."""
    bare = tmp_path / "bare.html"
    text = report.read_text(encoding="utf-8")
    bare.write_text(re.sub(r"<script[^>]*>.*?</script>", "", text, flags=re.S), encoding="utf-8")
    shots = {}
    for name, page in (("on", report), ("off", bare)):
        png = tmp_path / f"{name}.png"
        res = _chromium(page, tmp_path, "--window-size=1280,1800", f"--screenshot={png}")
        assert png.is_file(), res.stderr[-2000:]
        shots[name] = _pixels(png)
    (traces, ink), (traces_off, ink_off) = shots["on"], shots["off"]
    assert traces_off == 0 and traces > 200, shots  # the curves exist only where drawn
    assert ink > ink_off + 5000, shots  # and the axes, ticks and labels around them
