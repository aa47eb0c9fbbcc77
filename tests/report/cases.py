"""Shared helpers of the report tests: the CLI in a subprocess."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import Any

ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "COLUMNS": "160"}


def run_cli(*args: str, cwd: Path | None = None) -> Any:
    """``rheolin ARGS`` in a subprocess (text output, 10 minutes at most)."""
    return subprocess.run(
        [sys.executable, "-m", "rheolin.cli", *args],
        capture_output=True, text=True, env=ENV, timeout=600, cwd=cwd,
    )  # fmt: skip
