"""In-process CLI for the reliability tests: ``typer.testing.CliRunner`` (the same error
contract as the ``rheolin`` script, without a new interpreter per case)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from rheolin.cli import app
from rheolin.data import example_text


@pytest.fixture(autouse=True)
def _allow_underflow():
    with np.errstate(under="ignore"):
        yield


@pytest.fixture
def invoke():
    """``invoke(*args) -> Result`` with ``exit_code``, ``stdout``, ``stderr``."""
    runner = CliRunner()

    def call(*args: str, env: dict[str, str] | None = None):
        return runner.invoke(app, [str(a) for a in args], catch_exceptions=False, env=env)

    return call


@pytest.fixture
def rotor(tmp_path) -> Path:
    p = tmp_path / "rotor.toml"
    p.write_text(example_text("rotor"))
    return p
