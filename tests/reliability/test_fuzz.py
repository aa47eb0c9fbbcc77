"""The fuzzing suite: malformed model files and command lines (fuzz_cases.py) through the CLI
in-process. Every case ends in exit 2 with a message naming a field, or in an honest result
(0, or 1 with the results saying why), within the per-example deadline and a small solve
memory budget (sizes beyond it are refused, not allocated). bench/fuzz.py runs the same
strategies 10,000+ times."""

from __future__ import annotations

import sys
from datetime import timedelta
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

sys.path.insert(0, str(Path(__file__).parent))
from fuzz_cases import check_outcome, mutated_model, run_arguments

FUZZ = settings(
    deadline=timedelta(seconds=10),
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
    database=None,
)


@pytest.fixture(autouse=True)
def _small_budget(monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)  # `--out ''` is the working directory
    monkeypatch.setenv("RHEOLIN_SOLVE_MEMORY", "256 MB")
    monkeypatch.setenv("RHEOLIN_MEMORY_BUDGET", "256 MB")


@settings(FUZZ, max_examples=250)
@given(text=mutated_model())
def test_mutated_model_files_are_refused_naming_a_field_or_valid(invoke, tmp_path, text):
    path = tmp_path / "m.toml"
    path.write_text(text)
    res = invoke("validate", path)
    check_outcome(res.exit_code, res.stdout, res.stderr)


@settings(FUZZ, max_examples=60)
@given(args=run_arguments())
def test_hostile_run_arguments_end_in_exit_2_or_an_honest_result(invoke, rotor, tmp_path, args):
    (tmp_path / "file").write_text("not a directory")
    res = invoke(*[a.format(model=rotor, tmp=tmp_path) for a in args])
    kind = check_outcome(res.exit_code, res.stdout, res.stderr)
    if kind != "refused":
        assert "wrote" in res.stdout
