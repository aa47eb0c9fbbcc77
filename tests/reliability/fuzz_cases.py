"""Malformed model files and command lines for the fuzzing suite (tests/reliability/test_fuzz.py,
bench/fuzz.py): hypothesis strategies, and the check every outcome must pass.

A model is one of the embedded examples read into a dict and mutated at a random place: wrong
types, units and dimensions, out-of-range and non-finite numbers, missing and duplicated
entries, unknown keys, broken references, hostile strings (Rich markup, emoji codes, control
characters, very long text) and sizes. The mutated dict is written back as TOML.
"""

from __future__ import annotations

import copy
import re
import tomllib
from typing import Any

import tomli_w
from hypothesis import strategies as st

from rheolin.data import example_text

#: The contract: user errors exit 2, success 0, an honest failure 1; never 3 (a bug).
ALLOWED_EXIT = {0, 1, 2}

#: An ``error:`` message must name where the problem is: a field path, an option, or one of
#: the model-level checks.
FIELD = re.compile(
    r"(\b(model|harmonics|shafts|rigid_bodies|condensed_bodies|meshes|forces|loads|mass|"
    r"torques|rigid_links|bearings|fe|condense|interface|spec|memory|input)\b[\[.:]"
    r"|--[a-z-]+|\.toml|invalid model file|rheolin \w+:|RHEOLIN_[A-Z_]+|DIRECTORY:"
    r"|\b(bearing|mesh|torque|body)s? '[^']+'"
    r"|\b(Shaft|Disk|Bearing|Seal)Element\w*|\bPointMass\w*|ROSS file)"
)

HOSTILE_TEXT = [
    "",
    " ",
    "[red]x[/red]",
    "[mass]",
    ":100:",
    "6000:100:100rpm",
    "\x1b[31mred",
    "a\tb",
    "x" * 5000,
    "nan",
    "inf",
    "-inf",
    "1e400",
    "3 kg",
    "30",
    "-5 mm",
    "0 N/m",
    "1e30 N/m",
    "2e8 N/m",
    "20 deg",
    "95 deg",
    "3000 rpm",
    "input",
    "rotor",
    "../../etc/passwd",
    "/dev/null",
    "1/0",
]
HOSTILE_VALUES: list[Any] = [
    *HOSTILE_TEXT,
    True,
    0,
    -1,
    1,
    10**9,
    10**30,
    -(10**9),
    0.0,
    -0.0,
    1e-300,
    1e300,
    -1e300,
    2.5,
    [],
    [1, 2],
    ["3 kg", "2 m"],
    [[1, 2], [3, 4]],
    {},
    {"x": 1},
]


MUTATIONS = [
    *["replace"] * 3,
    *["delete", "duplicate", "unknown", "rename", "scale", "size"],
]


def example_document(name: str = "rotor") -> dict[str, Any]:
    """An embedded example read into a dict."""
    return tomllib.loads(example_text(name))


def _paths(doc: Any, prefix: tuple = ()) -> list[tuple]:
    """Every path to a value, table or list in ``doc``."""
    out = [prefix] if prefix else []
    if isinstance(doc, dict):
        for k, v in doc.items():
            out += _paths(v, (*prefix, k))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            out += _paths(v, (*prefix, i))
    return out


def _get(doc: Any, path: tuple) -> Any:
    for p in path:
        doc = doc[p]
    return doc


def _names(doc: dict[str, Any]) -> list[str]:
    names = []
    for table in ("shafts", "rigid_bodies", "condensed_bodies", "meshes", "forces"):
        items = doc.get(table, [])
        for item in items if isinstance(items, list) else []:
            if isinstance(item, dict) and isinstance(item.get("name"), str):
                names.append(item["name"])
    return names


@st.composite
def mutated_model(
    draw: st.DrawFn, names: tuple[str, ...] = ("rotor", "gearbox", "preloaded")
) -> str:
    """TOML text of an example with one to three mutations."""
    doc = example_document(draw(st.sampled_from(names)))
    for _ in range(draw(st.integers(1, 3))):
        paths = _paths(doc)
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent, key = _get(doc, path[:-1]), path[-1]
        kind = draw(st.sampled_from(MUTATIONS))
        if kind == "replace":
            parent[key] = copy.deepcopy(draw(st.sampled_from(HOSTILE_VALUES)))
        elif kind == "delete":
            del parent[key]
        elif kind == "duplicate" and isinstance(parent, list):
            parent.append(copy.deepcopy(parent[key]))
        elif kind == "unknown" and isinstance(parent, dict):
            parent[draw(st.sampled_from(["colour", "elastic_modulos", "Order", "[x]"]))] = 1
        elif kind == "rename":
            parent[key] = draw(st.sampled_from([*_names(doc), "nowhere", "[b]x"]))
        elif kind == "scale" and isinstance(parent[key], int | float):
            if not isinstance(parent[key], bool):
                factor = draw(st.sampled_from([-1.0, 0.0, 1e-9, 1e3, 1e12]))
                parent[key] = parent[key] * factor
        elif kind == "size":
            size_paths = [p for p in _paths(doc) if p[-1] in ("order", "stiffness_harmonics")]
            size_paths += [p for p in _paths(doc) if p[-1] == "positions" and len(p) == 3]
            if size_paths:
                target = draw(st.sampled_from(size_paths))
                if target[-1] == "positions":  # a shaft too long to assemble
                    n = draw(st.sampled_from([200_000, 10**6]))
                    _get(doc, target[:-1])["positions"] = f"{' '.join(map(str, range(n)))} mm"
                else:
                    _get(doc, target[:-1])[target[-1]] = draw(
                        st.sampled_from([10**6, 10**9, 2**62, -3])
                    )
    try:
        return tomli_w.dumps(doc)
    except (TypeError, ValueError):  # e.g. a list mixing tables and values: write garbage
        return "this = [is not toml"


SPEEDS = st.sampled_from(
    ["3000rpm", "3000", "-5rpm", "0rpm", "1e-30rpm", "1e12rpm", "nan rpm", "inf rpm", "3 kg",
     "6000:100:100rpm", "[red]5rpm", ":100:rpm", "", "1e400rpm", "2000 rpm", "50 Hz"]
)  # fmt: skip
NUMBERS = st.sampled_from(["x", "-1", "0", "1", "2", "1e9", "inf", "nan", "-inf", "1e-300", ""])
OUT = st.sampled_from(["{tmp}/o", "{tmp}/file", "{tmp}/file/sub", "", "{tmp}/" + "d" * 300])


@st.composite
def run_arguments(draw: st.DrawFn) -> list[str]:
    """``rheolin run MODEL ...`` with some hostile options (placeholders ``{model}``,
    ``{tmp}``); always ``--stability off --no-plots`` and order 1 to stay fast when valid."""
    args = ["run", "{model}", "--no-plots", "--stability", "off", "--harmonics", "1"]
    if draw(st.booleans()):
        args += ["--speed", draw(SPEEDS)]
    if draw(st.booleans()):
        args += ["--max-order", draw(NUMBERS)]
    if draw(st.booleans()):
        args += ["--rtol", draw(NUMBERS)]
    if draw(st.booleans()):
        args += ["--method", draw(st.sampled_from(["auto", "gmres", "lti", "magic", "[b]"]))]
    if draw(st.booleans()):
        args += ["--nodes", draw(st.sampled_from(["rotor:1", "rotor:99", "[x]:1", ",,"]))]
    args += ["--out", draw(OUT)]
    return args


def check_outcome(exit_code: int, stdout: str, stderr: str) -> str:
    """Assert the contract for one case; return its class (``"ok"``, ``"refused"``,
    ``"failed"``)."""
    assert exit_code in ALLOWED_EXIT, (exit_code, stderr[-2000:])
    assert "Traceback" not in stdout + stderr, stderr[-2000:]
    if exit_code == 2:
        lines = [ln for ln in stderr.splitlines() if ln.strip()]
        assert lines and lines[0].startswith("error: "), stderr[-2000:]
        assert FIELD.search(stderr), stderr[-2000:]
        return "refused"
    return "ok" if exit_code == 0 else "failed"
