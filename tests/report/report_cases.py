"""Shared helpers of the report tests: the CLI in a subprocess."""

from __future__ import annotations

import importlib.util
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


def study_cases() -> Any:
    """tests/study/study_cases.py as a module (loaded by path: tests/study, which has a
    conftest.py, stays off sys.path)."""
    path = Path(__file__).parents[1] / "study" / "study_cases.py"
    spec = importlib.util.spec_from_file_location("rheolin_study_cases", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
