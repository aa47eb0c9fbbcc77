"""Fixtures of the study tests: the band model as a file."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from study_cases import BAND


@pytest.fixture(scope="module")
def band_file(tmp_path_factory):
    """``BAND`` written to a model file."""
    path = tmp_path_factory.mktemp("model") / "band.toml"
    path.write_text(BAND)
    return path
