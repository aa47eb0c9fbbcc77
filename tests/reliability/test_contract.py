"""The CLI's error contract, case by case: user errors exit 2 with one plain line naming the
field before any work, internal errors exit 3 (traceback behind --debug), Ctrl-C exits 130
and says what was kept; Rich markup never eats user text."""

from __future__ import annotations

import json

import numpy as np
import pytest

import rheolin.results as results_pkg
from rheolin.data import example_text
from rheolin.io import parse_model


def _one_line_error(res, *needles: str) -> str:
    """The single ``error:`` line of a refused command, which must mention ``needles``."""
    assert res.exit_code == 2, (res.exit_code, res.stdout, res.stderr)
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), res.stderr
    assert "Traceback" not in res.stderr + res.stdout
    for n in needles:
        assert n in lines[0], (n, lines[0])
    return lines[0]


@pytest.fixture
def no_compute(monkeypatch):
    """Fail the test if a refused command started computing."""

    def boom(*a, **k):
        raise AssertionError("the computation started before the input was checked")

    monkeypatch.setattr(results_pkg, "solve_point", boom)


def test_output_path_is_checked_before_computing(invoke, rotor, tmp_path, no_compute):
    afile = tmp_path / "afile"
    afile.write_text("keep me")
    _one_line_error(invoke("run", rotor, "--out", afile), "--out", "existing file")
    _one_line_error(invoke("run", rotor, "--out", afile / "sub"), "--out", "not a directory")
    _one_line_error(invoke("campbell", rotor, "--speeds", "1000rpm", "--out", afile), "--out")
    _one_line_error(invoke("sweep", rotor, "--speeds", "1000rpm", "--out", afile), "--out")
    assert afile.read_text() == "keep me"


@pytest.mark.parametrize(
    "case, needles",
    [
        (("run", "{m}", "--max-order", "inf"), ("--max-order", "inf")),
        (("run", "{m}", "--max-order", "nan"), ("--max-order",)),
        (("run", "{m}", "--rtol", "0"), ("--rtol",)),
        (("run", "{m}", "--harmonics", "x"), ("--harmonics", "integer")),
        (("run", "{m}", "--method", "magic"), ("--method", "magic")),
        (("run", "{m}", "--speed", "-5rpm"), ("--speed",)),
        (("run", "{m}", "--speed", "3000"), ("--speed", "without a unit")),
        (("run", "{m}", "--nodes", "nowhere:9"), ("--nodes", "nowhere:9")),
        (("campbell", "{m}", "--speeds", "1000:2000:500rpm", "--fmax", "-5"), ("--fmax", "-5")),
        (("sweep", "{m}", "--speeds", "6000:100:100rpm"), ("--speeds", "6000:100:100rpm")),
        (("sweep", "{m}", "--speeds", "1000rpm", "--workers", "0"), ("--workers",)),
        (("run", "{m}", "--harmonics", "100000000"), ("order", "memory budget")),
        (("run", "{m}", "--out", "{t}/" + "d" * 300), ("--out", "300 bytes")),  # bench/fuzz.py
    ],
)
def test_bad_options_exit_2_naming_the_option(invoke, rotor, tmp_path, no_compute, case, needles):
    args = [*[a.format(m=rotor, t=tmp_path) for a in case[:2]], "--out", str(tmp_path / "o")]
    args += [a.format(m=rotor, t=tmp_path) for a in case[2:]]  # a later --out wins
    _one_line_error(invoke(*args), *needles)
    assert not (tmp_path / "o").exists()


def test_rich_markup_and_emoji_codes_are_printed_as_written(invoke, rotor, tmp_path):
    # "6000:100:100rpm" holds the emoji code ":100:"; unit errors hold "[mass]"
    line = _one_line_error(invoke("sweep", rotor, "--speeds", "6000:100:100rpm"))
    assert "6000:100:100rpm" in line
    text = example_text("rotor").replace('density = "7850 kg/m^3"\n', 'density = "7850 kg"\n', 1)
    (tmp_path / "bad.toml").write_text(text)
    _one_line_error(invoke("validate", tmp_path / "bad.toml"), "shafts[0].density", "[mass]")


def test_a_name_with_markup_prints_as_in_the_files(invoke, tmp_path):
    name = "[red]drive[/red] [b]end"
    text = example_text("rotor").replace('"drive_end"', json.dumps(name))
    (tmp_path / "m.toml").write_text(text)
    res = invoke("run", tmp_path / "m.toml", "--out", tmp_path / "o", "--no-plots")
    assert res.exit_code == 0, res.stderr
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert name in summary["bearings"]
    assert "[red]drive[/red]" in res.stdout


def test_pressure_angle_refused_by_validate_as_by_run(invoke, tmp_path, no_compute):
    text = example_text("gearbox").replace(
        'pressure_angle = "20 deg"', 'pressure_angle = "95 deg"', 1
    )
    (tmp_path / "g.toml").write_text(text)
    a = _one_line_error(invoke("validate", tmp_path / "g.toml"), "meshes[0].pressure_angle")
    b = _one_line_error(invoke("run", tmp_path / "g.toml", "--out", tmp_path / "o"))
    assert a == b


def test_model_without_bearings_is_refused_naming_the_body_and_direction(invoke, tmp_path):
    """Nothing holds the body laterally or in tilt: no steady state (its mean position is
    undetermined, and its zero Floquet exponents were once reported "stable")."""
    (tmp_path / "free.toml").write_text(FREE_BODY)
    for cmd in ("validate", "run"):
        line = _one_line_error(
            invoke(cmd, tmp_path / "free.toml", *(["--out", tmp_path / "o"] * (cmd == "run"))),
            "bearings: no steady state", "body 'r'", "laterally", "ux, uy",
        )  # fmt: skip
        assert "tilts" in line
    assert not (tmp_path / "o").exists()


def test_internal_error_exits_3_with_traceback_only_behind_debug(
    invoke, rotor, tmp_path, monkeypatch
):
    def bug(*a, **k):
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr(results_pkg, "solve_point", bug)
    res = invoke("run", rotor, "--out", tmp_path / "o")
    assert res.exit_code == 3
    assert "internal error: ZeroDivisionError: a bug" in res.stderr
    assert "Traceback" not in res.stderr and "--debug" in res.stderr
    res = invoke("--debug", "run", rotor, "--out", tmp_path / "o")
    assert res.exit_code == 3 and "Traceback" in res.stderr
    assert not (tmp_path / "o").exists()


def test_ctrl_c_exits_130_and_says_what_was_kept(invoke, rotor, tmp_path, monkeypatch):
    (tmp_path / "o").mkdir()
    (tmp_path / "o" / "summary.json").write_text('{"earlier": true}')

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(results_pkg, "solve_point", interrupted)
    res = invoke("run", rotor, "--out", tmp_path / "o")
    assert res.exit_code == 130
    assert "interrupted: nothing written" in res.stderr and "unchanged" in res.stderr
    assert (tmp_path / "o" / "summary.json").read_text() == '{"earlier": true}'


@pytest.mark.parametrize("sigint", ["handled", "ignored"])
def test_ctrl_c_inside_a_finalizer_still_interrupts_the_command(
    invoke, rotor, tmp_path, monkeypatch, sigint
):
    """Python drops a KeyboardInterrupt raised in a weakref callback or ``__del__`` (it
    prints "Exception ignored" with a traceback); the command gets it back and ends with
    exit 130, saying what was kept, instead of running on. Also where SIGINT is ignored (a
    batch job, a script's ``cmd &``): there the interrupt is a SIGTERM's."""
    import signal

    old = signal.signal(
        signal.SIGINT, signal.default_int_handler if sigint == "handled" else signal.SIG_IGN
    )
    try:
        _finalizer_interrupt(invoke, rotor, tmp_path, monkeypatch)
    finally:
        signal.signal(signal.SIGINT, old)


def _finalizer_interrupt(invoke, rotor, tmp_path, monkeypatch):
    import time

    class Finalized:
        def __del__(self):
            raise KeyboardInterrupt

    def solve(*a, **k):
        Finalized()  # dropped at once: its KeyboardInterrupt is unraisable
        t_end = time.monotonic() + 20
        while time.monotonic() < t_end:  # a computation that would go on
            time.sleep(0.01)
        raise AssertionError("the interrupt was lost")

    monkeypatch.setattr(results_pkg, "solve_point", solve)
    res = invoke("run", rotor, "--out", tmp_path / "o")
    assert res.exit_code == 130, res.stderr
    assert "interrupted: nothing written" in res.stderr and "Traceback" not in res.stderr
    assert not (tmp_path / "o").exists()


def test_missing_material_constants_are_errors_unless_a_material_is_named(tmp_path):
    text = example_text("rotor").replace('elastic_modulus = "210 GPa"\n', "")
    with pytest.raises(ValueError, match=r"shafts\[0\]\.elastic_modulus: required"):
        parse_model(text)
    named = text.replace("[[shafts]]\n", '[[shafts]]\nmaterial = "steel"\n', 1)
    E = parse_model(named).model.bodies["rotor"]
    ref = parse_model(example_text("rotor")).model.bodies["rotor"]
    assert np.allclose(E.positions, ref.positions)
    a = parse_model(named).model.assemble(100.0).system.K[0].toarray()
    b = parse_model(example_text("rotor")).model.assemble(100.0).system.K[0].toarray()
    assert np.allclose(a, b, rtol=1e-12, atol=0)  # steel's E = 210 GPa, as the example


def test_a_plain_number_diameter_in_metres_is_refused(tmp_path):
    text = example_text("gearbox").replace('outer_diameter = "30 mm"', "outer_diameter = 30", 1)
    with pytest.raises(ValueError, match=r"shafts\[0\]\.outer_diameter: .*30 m.*'30 mm'"):
        parse_model(text)


FREE_BODY = """
[model]
speed = "1000 rpm"

[[rigid_bodies]]
name = "r"
position = [0, 0, 0]
mass = 2.0
inertia = [0.01, 0.01, 0.02]

[[forces]]
name = "f"
body = "r"
node = 0
force = [1, 0, 0]
order = 1
"""


def test_condensed_body_with_an_indefinite_mass_is_refused():
    from rheolin.errors import ModelError
    from rheolin.mechanics.condensed import CondensedBody

    K = np.eye(6) * 1e6
    M = np.eye(6)
    assert CondensedBody(nodes=[0], M=M, K=K).M.shape == (6, 6)
    bad = M.copy()
    bad[2, 2] = -1e-3  # one negative direction: negative kinetic energy
    with pytest.raises(ModelError, match=r"`M` \(the mass matrix\) must be positive semidef"):
        CondensedBody(nodes=[0], M=bad, K=K)
    with pytest.raises(ModelError, match="symmetric"):
        CondensedBody(nodes=[0], M=M + np.triu(np.ones((6, 6)), 1), K=K)


def test_sizes_in_the_file_are_refused_before_allocating(invoke, tmp_path, no_compute):
    g = example_text("gearbox")
    text = g.replace("order = 3 ", "order = 1000000000 ").replace("max_order = 200 ", "", 1)
    (tmp_path / "o.toml").write_text(text)
    _one_line_error(invoke("validate", tmp_path / "o.toml"), "harmonics.order", "memory budget")
    big = g.replace("stiffness_harmonics = 5", "stiffness_harmonics = 1000000000", 1)
    (tmp_path / "s.toml").write_text(big)
    _one_line_error(invoke("validate", tmp_path / "s.toml"), "stiffness_harmonics", "500")


def test_lti_on_a_time_varying_model_is_an_input_error(invoke, rotor, tmp_path):
    """Found by bench/fuzz.py: it used to exit 3 (an internal error)."""
    _one_line_error(invoke("run", rotor, "--method", "lti", "--out", tmp_path / "o"), "lti")
    assert not (tmp_path / "o").exists()
