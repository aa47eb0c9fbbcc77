"""The rest of the surface for the fuzzing suite (tests/reliability/test_fuzz.py, bench/fuzz.py):
every other subcommand's options, condense specs, ROSS files, ``sweep --vary``, the
environment, and the Python entry points (``rl.solve``, ``rl.floquet``, ``Model.add_*``).

A CLI case is a list of arguments with placeholders (``{model}``, ``{tmp}``, ``{spec}``,
``{ross}``) and, for some, environment variables; :func:`fuzz_cases.check_outcome` judges it.
An API case is a callable; :func:`check_call` judges it: a result, or a ``ValueError``
(``ModelError``), ``TypeError`` or ``MemoryBudgetError`` whose message names the argument.
"""

from __future__ import annotations

import copy
import tomllib
from collections.abc import Callable
from typing import Any

import numpy as np
import tomli_w
from fuzz_cases import HOSTILE_TEXT, HOSTILE_VALUES, NUMBERS, OUT, SPEEDS
from hypothesis import strategies as st

#: Tags of the CLI categories (bench/fuzz.py counts them apart).
CATEGORIES = ("frf", "modes", "campbell", "critical", "sweep", "condense", "ross", "env", "draw",
              "report")  # fmt: skip

DOFS = st.sampled_from(
    ["rotor:1:ux", "rotor:1:uy", "rotor:0:phiz", "rotor:9:ux", "rotor:1:uq", "nowhere:0:ux",
     "[b]x:0:ux", "rotor::ux", "rotor:-1:ux", "rotor:1", ":::", ""]
)  # fmt: skip
FREQUENCIES = st.sampled_from(
    ["10:500:50Hz", "0:200:40Hz", "1:2:1Hz", "500:10:10Hz", "10:500:0Hz", "nan:1:1Hz",
     "10:500:50", "1e9:1e10:1e9Hz", "10:1e7:1Hz", "[red]1:2:1Hz", "", "5 Hz", "10,20,30Hz"]
)  # fmt: skip
ORDERS = st.sampled_from(["0", "1", "2", "-1", "20", "100000", "x", "1e3"])
CSPEEDS = st.sampled_from(
    ["0:3000:1000rpm", "1000:3000:1000rpm", "0rpm", "-1000:0:500rpm", "0:1e12:1e11rpm",
     "3000:0:1000rpm", "0:6000:0rpm", "nan:1:1rpm", "1000,2000rpm", "[b]1000rpm", ""]
)  # fmt: skip
STIFFNESS = st.sampled_from(
    ["1e5:1e10:5", "1e5:1e10:5 N/m", "1e10:1e5:5", "0:1e10:5", "1e5:1e10:1", "1e5:1e10:100000",
     "1e5:1e10:5 kg", "-1:1:3", "nan:1e6:3", "1e5:1e10", "x"]
)  # fmt: skip
VARY = st.sampled_from(
    ["bearings.free_end.stiffness=1e7:5e7:2 N/m", "bearings.drive_end.stiffness[0]=1e7,2e7 N/m",
     "bearings.free_end.damping=100,500 N*s/m", "shafts.rotor.disks[0].unbalance=10,30 g*mm",
     "bearings.drive_end.stiffness[9]=1e7,2e7 N/m", "bearings.nowhere.stiffness=1e7,2e7 N/m",
     "bearings.drive_end.stiffness=1e7:5e7:2 kg", "bearings.drive_end.stiffness=5e7:1e7:2 N/m",
     "bearings.drive_end.stiffness=1e7,1e7 N/m", "bearings.drive_end.stiffness=-1e7,1e7 N/m",
     "shafts.rotor.density=7000,8000 kg/m^3", "shafts.rotor.density=0,8000 kg/m^3",
     "harmonics.order=1,2", "harmonics.order=1,1e9", "model.speed=1000,2000 rpm",
     "disks.rotor:1.unbalance=0,1e9 g*mm", "shafts.rotor.positions=1,2 m", "=1,2", "x",
     "shafts.rotor.disks[0].inertia[0]=1,2 kg*m^2", "bearings.drive_end.damping=0:1e3:2"]
)  # fmt: skip
ENV_VALUES = st.sampled_from(
    ["4 GB", "256 MB", "1", "0", "-5GB", "banana", "1e400 GB", "nan", "", " ", "1 TiB", "2e9",
     "[red]1 GB"]
)  # fmt: skip

DRAWINGS = ["{tmp}/d.png", "{tmp}/d.svg", "{tmp}/d.pdf", "{tmp}/d.txt", "{tmp}", "{tmp}/d",
            "{tmp}/file/d.png", "{tmp}/no/d.png", "", "[b]d.png"]  # fmt: skip
#: Result directories for ``report`` (:func:`write_results`; ``run`` only when a caller
#: computed one there) and other paths.
RESULTS = ["{res}/empty", "{res}/garbage", "{res}/typed", "{res}/nested", "{res}/foreign",
           "{res}/run", "{tmp}/file", "{tmp}/no", "{model}", ""]  # fmt: skip
OPERATING = ["2800:3200rpm", "3000rpm", "3200:2800rpm", "0:1e12rpm", "nan:1rpm", "-5:5rpm",
             "1:2:3rpm", "3000", "banana"]  # fmt: skip
REPORTS = ["{tmp}/r.html", "{tmp}", "{tmp}/file/r.html", "{tmp}/no/r.html", "{tmp}/r.txt"]

#: Mostly valid values, so that the cases reach the computation (and its refusals) as often
#: as the option parsing.
GOOD_SPEEDS = st.sampled_from(["3000rpm", "1500 rpm", "50 Hz", "200 rad/s"])
GOOD_DOFS = st.sampled_from(["rotor:1:ux", "rotor:1:uy", "rotor:2:phix", "rotor:0:uz"])
GOOD_VARY = st.sampled_from(
    ["bearings.free_end.stiffness=1e7:5e7:2 N/m", "harmonics.order=1,2",
     "shafts.rotor.disks[0].unbalance=10,30 g*mm"]
)  # fmt: skip


@st.composite
def cli_case(draw: st.DrawFn) -> tuple[str, list[str], dict[str, str]]:
    """``(category, arguments, environment)`` of one hostile command line."""
    kind = draw(st.sampled_from(CATEGORIES))
    env: dict[str, str] = {}
    out = ["--out", draw(OUT)]
    if kind == "frf":
        speed = draw(st.one_of(GOOD_SPEEDS, SPEEDS))
        args = ["frf", "{model}", "--speed", speed, "--frequencies", draw(FREQUENCIES)]
        args += ["--input", draw(st.one_of(GOOD_DOFS, DOFS))]
        if draw(st.booleans()):
            args += ["--output", draw(st.one_of(GOOD_DOFS, DOFS))]
        if draw(st.booleans()):
            args += ["--order", draw(ORDERS)]
        if draw(st.booleans()):
            args += ["--unbalance"]
        args += ["--stability", draw(st.sampled_from(["off", "off", "auto", "sideways"]))]
    elif kind == "modes":
        args = ["modes", "{model}", "--speed", draw(st.one_of(GOOD_SPEEDS, SPEEDS))]
        if draw(st.booleans()):
            args += ["--count", draw(NUMBERS)]
    elif kind == "campbell":
        args = ["campbell", "{model}", "--speeds", draw(CSPEEDS), "--stability", "off"]
        if draw(st.booleans()):
            args += ["--fmax", draw(NUMBERS)]
    elif kind == "critical":
        args = ["critical-map", "{model}", "--stiffness", draw(STIFFNESS)]
        if draw(st.booleans()):
            args += ["--bearing", draw(st.sampled_from(["drive_end", "free_end", "no", "[b]"]))]
        if draw(st.booleans()):
            args += ["--count", draw(NUMBERS)]
    elif kind == "sweep":
        args = ["sweep", "{model}", "--speeds", draw(st.sampled_from(["1000,2000rpm", "0rpm"]))]
        args += ["--workers", "1", "--stability", "off", "--no-stability-map"]
        args += draw(st.sampled_from([["--no-plots"], ["--no-plots"], [], ["--report"]]))
        if draw(st.booleans()):
            args += ["--refine-peaks"]
        for _ in range(draw(st.integers(1, 2))):
            args += ["--vary", draw(st.one_of(GOOD_VARY, VARY))]
    elif kind == "condense":
        args = ["condense", "{spec}"]
        out = ["--out", draw(st.sampled_from(["{tmp}/b.npz", "{tmp}/b.txt", "{tmp}/no/b.npz"]))]
    elif kind == "ross":
        args = ["import-ross", "{ross}"]
        out = draw(st.sampled_from([[], [], ["--out", "{tmp}/m.toml"], ["--out", "{tmp}"]]))
    elif kind == "draw":
        args = ["draw", "{model}", *draw(st.sampled_from([[], ["--nodes"]]))]
        out = draw(st.sampled_from([[], *[["--out", o] for o in DRAWINGS]]))
    elif kind == "report":
        args = ["report", draw(st.sampled_from(RESULTS))]
        if draw(st.booleans()):
            args += ["--operating", draw(st.one_of(st.sampled_from(OPERATING), SPEEDS))]
        if draw(st.booleans()):
            args += ["--model", draw(st.sampled_from(["{model}", "{ross}", "{tmp}", "{tmp}/no"]))]
        args += draw(st.sampled_from([[], ["--nodes"]]))
        out = draw(st.sampled_from([[], *[["--out", o] for o in REPORTS]]))
    else:  # environment variables, under validate or a fast run
        name = draw(st.sampled_from(["RHEOLIN_MEMORY_BUDGET", "RHEOLIN_SOLVE_MEMORY"]))
        env[name] = draw(ENV_VALUES)
        args = draw(
            st.sampled_from(
                [["validate", "{model}"],
                 ["run", "{model}", "--no-plots", "--harmonics", "1", "--stability", "auto"]]
            )
        )  # fmt: skip
        if args[0] == "validate":
            out = []
    return kind, args + out, env


# ---------------------------------------------------------------------- documents
def _mutate(doc: Any, draw: st.DrawFn, extra: list[Any]) -> Any:
    """One to three random mutations of a document (replace, delete, duplicate, type)."""
    from fuzz_cases import _get, _paths

    for _ in range(draw(st.integers(0, 2))):  # none: the valid document, run through
        paths = _paths(doc)
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent, key = _get(doc, path[:-1]), path[-1]
        kind = draw(st.sampled_from(["replace", "replace", "delete", "duplicate", "unknown"]))
        if kind == "replace":
            parent[key] = copy.deepcopy(draw(st.sampled_from([*HOSTILE_VALUES, *extra])))
        elif kind == "delete":
            del parent[key]
        elif kind == "duplicate" and isinstance(parent, list):
            parent.append(copy.deepcopy(parent[key]))
        elif kind == "unknown" and isinstance(parent, dict):
            parent[draw(st.sampled_from(["colour", "Modes", "[x]"]))] = 1
    return doc


SPEC = {
    "fe": {"format": "matrix-market", "stiffness": "K.mtx", "mass": "M.mtx", "nodes": "nodes.csv"},
    "condense": {"modes": 6, "cutoff": "20 kHz"},
    "interface": [
        {"name": "left", "reference": ["0 mm", "25 mm", "20 mm"],
         "box": ["-1 mm", "-1 m", "-1 m", "1 mm", "1 m", "1 m"]},
        {"name": "right", "reference": ["300 mm", "25 mm", "20 mm"], "kind": "rigid",
         "sphere": {"centre": ["300 mm", "25 mm", "20 mm"], "radius": "40 mm"}},
    ],
}  # fmt: skip
SPEC_VALUES = ["Mneg.mtx", "K.mtx", "abaqus", "-2 kHz", "0 Hz", 1000000, "left", "right",
               "nodes.csv", [0, 1, 2], {"nodes": [0]}, {"box": [0, 0, 0, 0, 0, 0]}]  # fmt: skip


@st.composite
def condense_spec(draw: st.DrawFn) -> str:
    """TOML text of a mutated condense spec (over the FE files of :func:`write_fe`)."""
    doc = _mutate(copy.deepcopy(SPEC), draw, SPEC_VALUES)
    try:
        return tomli_w.dumps(doc)
    except (TypeError, ValueError):
        return "fe = [not toml"


def write_fe(directory: Any) -> None:
    """A small steel block (scikit-fem) as Matrix Market files for the condense specs, and a
    mass matrix of the wrong sign."""
    import scipy.io as sio

    from rheolin.fe.solid import solid_model, tensor_block

    fe = solid_model(*tensor_block((0.3, 0.05, 0.04), (6, 2, 2)))
    sio.mmwrite(directory / "K.mtx", fe.K)
    sio.mmwrite(directory / "M.mtx", fe.M)
    sio.mmwrite(directory / "Mneg.mtx", -fe.M)
    np.savetxt(directory / "nodes.csv", fe.coordinates, delimiter=",")


def write_results(directory: Any) -> None:
    """Result directories ``report`` must read or refuse (:data:`RESULTS`): empty, files
    that are not what they are named, tables with the wrong types, nesting beyond any
    reader, and a netCDF file of another command under a run's name."""
    import json
    from pathlib import Path

    import xarray as xr

    d = Path(directory)
    for name in ("empty", "garbage", "typed", "nested", "foreign"):
        (d / name).mkdir(parents=True, exist_ok=True)
    (d / "garbage" / "summary.json").write_text("{garbage")
    (d / "garbage" / "results.nc").write_bytes(b"CDF\x01 not netCDF")
    (d / "garbage" / "campbell.nc").write_text("")
    typed = {"converged": "yes", "warnings": 3, "speed_rpm": "x", "stability": [1],
             "operating_point": {"max_displacement_m": "x"}, "harmonics": None}  # fmt: skip
    (d / "typed" / "summary.json").write_text(json.dumps(typed))
    (d / "typed" / "sweep.json").write_text(json.dumps({"points": "x", "ranges": 5}))
    (d / "nested" / "sweep.json").write_text("[" * 100000 + "]" * 100000)
    ds = xr.Dataset({"x": ("n", np.arange(3.0))}, attrs={"speed_rpm": "x"})
    for name in ("results.nc", "modes.nc", "frf.nc", "campbell.nc", "sweep.nc"):
        ds.to_netcdf(d / "foreign" / name)
    (d / "foreign" / "sweep.json").write_text("null")


def ross_document() -> dict[str, Any]:
    """The ROSS rotor file of tests/io/test_ross.py as a dict."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parents[1] / "io"))
    from test_ross import ROSS_TEXT

    return tomllib.loads(ROSS_TEXT)


ROSS_VALUES = ["211 GPa", "7810 kg/m^3", [1e6, 2e6], [[1.0]], -1.0, 0.0, 1e300, 10**9, "n"]


@st.composite
def ross_text(draw: st.DrawFn) -> str:
    """TOML text of a mutated ROSS rotor file."""
    doc = _mutate(ross_document(), draw, ROSS_VALUES)
    try:
        return tomli_w.dumps(doc)
    except (TypeError, ValueError):
        return "x = [not toml"


# ---------------------------------------------------------------------- Python entry points
#: Exceptions an entry point may refuse bad arguments with (besides a result); a
#: ``MemoryBudgetError`` is a ``ValueError`` (a refused estimate, never a ``MemoryError``).
API_ERRORS = (ValueError, TypeError)


def _system() -> Any:
    import rheolin as rl

    return rl.PeriodicSystem(
        3.0,
        M={0: np.eye(3)},
        D={0: 0.05 * np.eye(3)},
        K={0: np.diag([4.0, 9.0, 16.0]), 1: 0.3 * np.eye(3)},
        f={1: np.array([1.0, 0.0, 0.5])},
    )


API_VALUES: list[Any] = [
    *HOSTILE_VALUES, None, -(10**7), 10**7, 2**40, float("nan"), float("inf"), -1.0, 1e-320,
    [0], [0, 2], [1, 1, 1], range(3), np.arange(5), np.array([[1, 2]]), "direct", "lti",
    "gmres", "perturbation", "auto", "dense", "sparse", "lattice", "magic", object(),
]  # fmt: skip

SOLVE_ARGS = {
    "harmonics": 3, "method": "auto", "rtol": 1e-10, "maxiter": None, "stability": False,
    "memory_budget": None, "backend": "auto", "x0": None,
}  # fmt: skip
FLOQUET_ARGS = {"harmonics": None, "method": "auto", "order": None, "k": None}

#: ``Model`` methods with valid arguments on a model with a shaft ``s`` (3 nodes) and a
#: rigid body ``r``; one argument is replaced by a hostile value.
MODEL_CALLS: dict[str, dict[str, Any]] = {
    "add_shaft": {"name": "t", "positions": [0.0, 0.2, 0.4], "outer_diameter": 0.04,
                  "material": "steel"},
    "add_shaft_layer": {"shaft": "s", "elements": [0], "outer_diameter": 0.08,
                        "inner_diameter": 0.05, "material": "steel"},
    "add_rigid_body": {"name": "b", "position": (0, 0, 0), "mass": 2.0,
                       "inertia": (0.01, 0.01, 0.02)},
    "add_disk": {"body": "s", "node": 1, "mass": 3.0, "inertia": (0.02, 0.02, 0.04),
                 "unbalance": 1e-4},
    "add_bearing": {"name": "x", "body": "s", "node": 0, "stiffness": 1e7, "damping": 100.0},
    "add_rolling_bearing": {"name": "y", "body": "s", "node": 2, "law": "elements",
                            "kind": "ball", "stiffness": 8e9, "elements": 9,
                            "clearance": 1e-5},
    "add_force": {"name": "f", "body": "s", "node": 1, "force": (0.0, -10.0, 0.0)},
    "add_torque": {"name": "t", "body": "s", "node": 0, "torque": 5.0},
    "add_rigid_link": {"name": "l", "body": "s", "node": 2, "other_body": "r",
                       "other_node": 0},
}  # fmt: skip


def base_model() -> Any:
    import rheolin as rl

    m = rl.Model()
    m.add_shaft("s", [0.0, 0.25, 0.5], outer_diameter=0.05, material="steel")
    m.add_rigid_body("r", (0, 0, 0.5), 1.0, (0.01, 0.01, 0.02))
    m.add_bearing("a", "s", 0, stiffness=1e8, damping=50.0)
    return m


@st.composite
def api_case(draw: st.DrawFn) -> tuple[str, Callable[[], Any], list[str]]:
    """``(label, call, names)``: an entry point with one or two hostile arguments
    (``names``: those arguments)."""
    import rheolin as rl

    which = draw(st.sampled_from(["solve", "floquet", "model", "model"]))
    if which in ("solve", "floquet"):
        args = dict(SOLVE_ARGS if which == "solve" else FLOQUET_ARGS)
        names = []
        for _ in range(draw(st.integers(1, 2))):
            key = draw(st.sampled_from(sorted(args)))
            args[key] = draw(st.sampled_from(API_VALUES))
            names.append(key)
        fn = rl.solve if which == "solve" else rl.floquet
        harmonics = args.pop("harmonics")

        def call() -> Any:
            return fn(_system(), harmonics, **args)

        return f"{which}({harmonics!r:.60}, {args!r:.200})", call, names
    method = draw(st.sampled_from(sorted(MODEL_CALLS)))
    kw = dict(MODEL_CALLS[method])
    key = draw(st.sampled_from(sorted(kw)))
    kw[key] = draw(st.sampled_from(API_VALUES))

    def add() -> Any:
        m = base_model()
        getattr(m, method)(**kw)
        if method not in ("add_rolling_bearing", "add_torque"):
            return m.assemble(100.0)
        return m

    return f"{method}({key}={kw[key]!r:.80})", add, [key]


def check_call(call: Callable[[], Any], names: list[str]) -> str:
    """Run an API case; ``"ok"`` or ``"refused"`` (an allowed exception whose message names
    an argument: one of ``names`` or a quoted one), else AssertionError (another exception:
    a bug; or a refusal that names nothing)."""
    import warnings

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with np.errstate(all="ignore"):
                call()
    except API_ERRORS as exc:
        text = str(exc)
        named = "`" in text or any(n in text for n in names)
        assert named, f"{type(exc).__name__} names no argument: {text[:300]}"
        return "refused"
    except Exception as exc:
        raise AssertionError(f"{type(exc).__name__}: {exc}") from None
    return "ok"


__all__ = [
    "API_ERRORS",
    "CATEGORIES",
    "HOSTILE_TEXT",
    "api_case",
    "check_call",
    "cli_case",
    "condense_spec",
    "ross_text",
    "write_fe",
    "write_results",
]
