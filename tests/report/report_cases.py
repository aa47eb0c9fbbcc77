"""Shared helpers of the report tests: the CLI in this process, the study cases."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from typing import Any


def run_cli(*args: str, cwd: Path | None = None) -> Any:
    """``rheolin ARGS`` in this process (tests/run_cli.py), 160 columns."""
    sys.path.insert(0, str(Path(__file__).parents[1]))
    from run_cli import cli

    return cli(*args, cwd=cwd, columns=160)


def study_cases() -> Any:
    """tests/study/study_cases.py as a module (loaded by path: tests/study, which has a
    conftest.py, stays off sys.path)."""
    path = Path(__file__).parents[1] / "study" / "study_cases.py"
    spec = importlib.util.spec_from_file_location("rheolin_study_cases", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
