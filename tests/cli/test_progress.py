"""Progress on stderr when it is not a terminal (a log): at most one line every
RHEOLIN_PROGRESS_INTERVAL seconds with the count, and one when a long step ends; the results
on stdout are untouched."""

from __future__ import annotations

import os
import re
import subprocess
import sys

from rheolin.data import example_text

ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "RHEOLIN_PROGRESS_INTERVAL": "0.001"}


def cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "rheolin.cli", *args], capture_output=True,
                          text=True, env=ENV, timeout=600, cwd=cwd)  # fmt: skip


def test_campbell_and_run_report_progress_in_a_log(tmp_path):
    (tmp_path / "rotor.toml").write_text(example_text("rotor"))
    res = cli("campbell", "rotor.toml", "--speeds", "0:3000:500rpm", "--stability", "off",
              "--out", "c", cwd=tmp_path)  # fmt: skip
    assert res.returncode == 0, res.stderr
    lines = res.stderr.splitlines()
    counts = [int(m.group(1)) for m in map(re.compile(r"(\d) of 7 speeds").search, lines) if m]
    assert counts == sorted(counts) and counts[-1] == 7  # in order, up to the last
    assert "done in" in lines[len(counts) - 1]  # the last line is the end of the step
    assert "Campbell diagram" not in res.stdout  # the log stays on stderr
    res = cli("run", "rotor.toml", "--out", "r", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert re.search(r"^solving at 3000 rpm: \d+ s \.\.\.$", res.stderr, re.M)
