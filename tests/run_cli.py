"""The ``rheolin`` command for tests: in this process, or through ``python -m rheolin.cli``.

``cli`` runs a command through the same application object as the ``rheolin`` script (Typer's
test runner: exit status, stdout and stderr apart), with NumPy's default floating-point error
handling as in a fresh process, and fails the test on an exception escaping the application;
``cli_process`` runs it in a subprocess, for the entry point itself and for anything that
needs a process (signals, pipes, environment read at start-up).
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "COLUMNS": "120"}


def cli(*args: object, cwd: Path | None = None, columns: int = 120) -> subprocess.CompletedProcess:
    """``rheolin ARGS`` in this process."""
    from typer.testing import CliRunner

    from rheolin.cli.app import app
    from rheolin.cli.common import console
    from rheolin.cli.errors import err

    # the consoles are made once per process: their width is set here as COLUMNS sets it in a
    # new process, and put back after
    widths = [(c, c._width) for c in (console, err)]
    try:
        for c, _ in widths:
            c.width = columns
        with (
            contextlib.chdir(cwd or Path.cwd()),
            np.errstate(divide="warn", over="warn", under="ignore", invalid="warn"),
        ):
            res = CliRunner().invoke(
                app, [str(a) for a in args], env={"COLUMNS": str(columns)}, catch_exceptions=False
            )
    finally:
        for c, w in widths:
            c._width = w
    argv = [str(a) for a in args]
    return subprocess.CompletedProcess(argv, res.exit_code, res.stdout, res.stderr)


def cli_process(
    *args: object, cwd: Path | None = None, env: dict[str, str] | None = None, timeout: float = 600
) -> subprocess.CompletedProcess:
    """``python -m rheolin.cli ARGS`` in a subprocess."""
    return subprocess.run(
        [sys.executable, "-m", "rheolin.cli", *[str(a) for a in args]],
        capture_output=True,
        text=True,
        env=env or ENV,
        cwd=cwd,
        timeout=timeout,
    )
