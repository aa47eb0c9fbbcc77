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


@settings(FUZZ, max_examples=100)
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


# ---------------------------------------------------------------------- the whole surface
from fuzz_semantic import check_semantic, semantic_case  # noqa: E402
from fuzz_surface import api_case, check_call, cli_case, condense_spec, ross_text  # noqa: E402


@pytest.fixture(scope="module")
def fe_files(tmp_path_factory):
    pytest.importorskip("skfem")
    from fuzz_surface import write_fe, write_results

    d = tmp_path_factory.mktemp("fe")
    write_fe(d)
    write_results(d / "res")
    return d


def run_cli_case(invoke, case, files: dict[str, str], tmp_path):
    """Invoke one :func:`fuzz_surface.cli_case` with its files; the result."""
    _, args, env = case
    argv = [a.format(tmp=tmp_path, **files) for a in args]
    return invoke(*argv, env=env)


@settings(FUZZ, max_examples=40)
@given(case=cli_case(), spec=condense_spec(), ross=ross_text())
def test_every_subcommand_and_the_environment_keep_the_contract(
    invoke, rotor, tmp_path, fe_files, case, spec, ross
):
    """frf, modes, campbell, critical-map, sweep --vary, condense specs, import-ross files,
    draw, report of hostile result directories and RHEOLIN_* variables: exit 2 naming the
    field, or an honest result."""
    (tmp_path / "file").write_text("not a directory")
    spec_path = fe_files / f"spec_{abs(hash(spec)) % 10**8}.toml"
    spec_path.write_text(spec)
    (tmp_path / "r.toml").write_text(ross)
    files = {"model": str(rotor), "spec": str(spec_path), "ross": str(tmp_path / "r.toml"),
             "res": str(fe_files / "res")}  # fmt: skip
    res = run_cli_case(invoke, case, files, tmp_path)
    check_outcome(res.exit_code, res.stdout, res.stderr)


@settings(FUZZ, max_examples=60)
@given(case=api_case())
def test_python_entry_points_refuse_bad_arguments_by_name(case):
    """``rl.solve``, ``rl.floquet`` and ``Model.add_*`` with hostile arguments: a result,
    or a ValueError/TypeError naming the argument; nothing else."""
    _, call, names = case
    check_call(call, names)


@settings(FUZZ, max_examples=40)
@given(case=semantic_case())
def test_duplicates_add_or_are_refused_as_the_format_says(case):
    """Semantic mutations (docs/model-format.md, duplicates and impossible physics): an
    entry that adds changes the matrices by exactly its own contribution; one that may not
    repeat, or cannot exist, is refused naming its field."""
    check_semantic(case)
