"""``rheolin condense SPEC.toml``: an FE body from its matrices -> a condensed ``.npz`` that a
model file takes as ``[[condensed_bodies]] path`` (docs/large-models.md).

The spec names the FE export, the interface node sets (by FE node numbers, a box or a
sphere) tied to rheolin nodes, and how many fixed-interface modes to keep::

    [fe]
    format = "abaqus"            # or "matrix-market" (nodes: a CSV of x, y, z; 3 DOF/node)
    stiffness = "job_STIF1.mtx"
    mass = "job_MASS1.mtx"
    nodes = "job.inp"            # *NODE blocks: FE node numbers and coordinates
    units = "mm-t-s"             # of the matrices and the .inp (Abaqus has none): or "SI"

    [condense]
    modes = 30
    cutoff = "2 kHz"             # keep every fixed-interface mode below (rule: 4 x fmax)
    spin_axis = [0, 0, 1]        # a rotating body; omit for a housing
    fixed = { box = ["-1 m", "-1 m", "-1 m", "1 m", "1 m", "0.001 m"] }   # clamped feet

    [[interface]]
    name = "bearing_A"
    reference = ["0 mm", "0 mm", "120 mm"]   # the rheolin node, in the FE axes
    kind = "average"             # RBE3-like (default) or "rigid" (RBE2-like)
    sphere = { centre = ["0 mm", "0 mm", "120 mm"], radius = "31 mm" }   # or nodes / box
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape

from ..errors import ModelError
from ..io.units import UnitError, to_si

__all__ = ["condense_command", "register"]

SPEC = typer.Argument(..., help="Condensation spec (TOML; see docs/large-models.md).")
OUT = typer.Option(..., "--out", "-o", help="The condensed body (.npz), written atomically.")
FORMATS = ("abaqus", "matrix-market")
#: The arguments of :func:`rheolin.fe.condense` and the spec fields that give them.
SPEC_FIELDS = {
    "`M`": "fe.mass",
    "`K`": "fe.stiffness",
    "`D`": "fe.damping",
    "`interface`": "interface",
    "`fixed`": "condense.fixed",
    "`modes`": "condense.modes",
    "`cutoff_hz`": "condense.cutoff",
}


def _length(value: Any, where: str) -> float:
    try:
        return to_si(value, "length")
    except UnitError as exc:
        raise ModelError(f"{where}: {exc}") from None


def _point(value: Any, where: str) -> np.ndarray:
    if not isinstance(value, list) or len(value) != 3:
        raise ModelError(f"{where}: expected three coordinates [x, y, z], got {value!r}")
    return np.array([_length(v, f"{where}[{i}]") for i, v in enumerate(value)])


def _table(doc: dict[str, Any], key: str, where: str) -> dict[str, Any]:
    value = doc.get(key, {})
    if not isinstance(value, dict):
        raise ModelError(f"{where}{key}: expected a table")
    return value


def _unknown(table: dict[str, Any], allowed: set[str], where: str) -> None:
    extra = sorted(set(table) - allowed)
    if extra:
        raise ModelError(
            f"{where}.{extra[0]}: unknown field (allowed: {', '.join(sorted(allowed))})"
        )


def _file(base: Path, value: Any, where: str) -> Path:
    if not isinstance(value, str) or not value:
        raise ModelError(f"{where}: expected a file path")
    p = Path(value)
    p = p if p.is_absolute() else base / p
    if not p.is_file():
        raise ModelError(f"{where}: no such file {str(p)!r}")
    return p


def read_fe(spec: dict[str, Any], base: Path) -> Any:
    """The :class:`~rheolin.fe.FEModel` of the spec's ``[fe]`` table."""
    from ..fe import FEModel
    from ..fe.abaqus import read_abaqus

    fe = _table(spec, "fe", "")
    _unknown(fe, {"format", "stiffness", "mass", "damping", "nodes", "units"}, "fe")
    fmt = fe.get("format", "abaqus")
    if fmt not in FORMATS:
        raise ModelError(f"fe.format: must be one of {', '.join(FORMATS)}, got {fmt!r}")
    stiffness = _file(base, fe.get("stiffness"), "fe.stiffness")
    mass = _file(base, fe.get("mass"), "fe.mass")
    damping = _file(base, fe["damping"], "fe.damping") if "damping" in fe else None
    if fmt == "matrix-market":
        import scipy.io as sio

        nodes = _file(base, fe.get("nodes"), "fe.nodes")
        try:
            xyz = np.loadtxt(nodes, delimiter=",", ndmin=2)
        except (ValueError, OSError, UnicodeDecodeError) as exc:
            raise ModelError(f"fe.nodes: cannot read a CSV of x, y, z per node ({exc})") from None
        if xyz.shape[1] != 3:
            raise ModelError("fe.nodes: expected a CSV of x, y, z per node (translations 3i+c)")

        def read(path: Path, key: str) -> Any:
            try:
                return sio.mmread(path)
            except (ValueError, OSError, UnicodeDecodeError, IndexError, TypeError) as exc:
                raise ModelError(f"fe.{key}: cannot read a Matrix Market file ({exc})") from None

        K, M = read(stiffness, "stiffness"), read(mass, "mass")
        D = read(damping, "damping") if damping is not None else None
        try:
            return FEModel.solid(K, M, xyz, D=D)
        except ModelError as exc:
            raise ModelError(f"fe: {exc}") from None
    nodes_path = _file(base, fe.get("nodes"), "fe.nodes") if "nodes" in fe else None
    units = fe.get("units", "SI")
    if not isinstance(units, str):
        raise ModelError(f"fe.units: expected a unit system, e.g. 'mm-t-s' or 'SI', got {units!r}")
    try:
        return read_abaqus(stiffness, mass, nodes=nodes_path, damping=damping, units=units)
    except ModelError as exc:
        raise ModelError(f"fe: {exc}") from None
    except (ValueError, OSError, UnicodeDecodeError, IndexError) as exc:
        raise ModelError(f"fe: cannot read the Abaqus export ({exc})") from None


def _select(fe: Any, table: dict[str, Any], where: str) -> np.ndarray:
    """FE node indices of a set: ``nodes`` (FE numbers), ``box`` (6 lengths), ``sphere``."""
    ways = [k for k in ("nodes", "box", "sphere") if k in table]
    if len(ways) != 1:
        raise ModelError(f"{where}: give exactly one of nodes, box, sphere")
    x = fe.coordinates
    if ways[0] == "nodes":
        ids = table["nodes"]
        if not isinstance(ids, list) or not all(isinstance(i, int) for i in ids):
            raise ModelError(f"{where}.nodes: expected a list of FE node numbers")
        idx = fe.node_index(ids)
    elif ways[0] == "box":
        b = table["box"]
        if not isinstance(b, list) or len(b) != 6:
            raise ModelError(f"{where}.box: expected [xmin, ymin, zmin, xmax, ymax, zmax]")
        lo = np.array([_length(v, f"{where}.box[{i}]") for i, v in enumerate(b[:3])])
        hi = np.array([_length(v, f"{where}.box[{i + 3}]") for i, v in enumerate(b[3:])])
        idx = np.flatnonzero(np.all((x >= lo) & (x <= hi), axis=1))
    else:
        s = table["sphere"]
        if not isinstance(s, dict) or set(s) != {"centre", "radius"}:
            raise ModelError(f"{where}.sphere: expected {{ centre = [x, y, z], radius = r }}")
        c = _point(s["centre"], f"{where}.sphere.centre")
        r = _length(s["radius"], f"{where}.sphere.radius")
        idx = np.flatnonzero(np.linalg.norm(x - c, axis=1) <= r)
    if idx.size == 0:
        raise ModelError(f"{where}: selects no FE node")
    return idx


def condense_spec(spec_path: Path) -> Any:
    """The :class:`~rheolin.fe.CondensedFE` a spec file describes."""
    from ..fe import Coupling, condense
    from ..io.loader import read_toml

    try:
        raw = spec_path.read_bytes()
    except OSError as exc:
        raise ModelError(f"{spec_path}: cannot read ({exc.strerror})") from None
    spec = read_toml(raw, str(spec_path))
    _unknown(spec, {"fe", "condense", "interface"}, "spec")
    base = spec_path.parent
    fe = read_fe(spec, base)
    c = _table(spec, "condense", "")
    _unknown(c, {"modes", "cutoff", "spin_axis", "fixed"}, "condense")
    modes = c.get("modes", 20)
    if isinstance(modes, bool) or not isinstance(modes, int) or modes < 0:
        raise ModelError(f"condense.modes: expected an integer >= 0, got {modes!r}")
    cutoff = None
    if "cutoff" in c:
        try:
            cutoff = to_si(c["cutoff"], "frequency") / (2 * np.pi)
        except UnitError as exc:
            raise ModelError(f"condense.cutoff: {exc}") from None
        if not (np.isfinite(cutoff) and cutoff > 0):
            raise ModelError(
                f"condense.cutoff: must be a frequency > 0 (e.g. '2 kHz'), got {c['cutoff']!r}"
            )
    axis = None
    if "spin_axis" in c:
        a = np.asarray(c["spin_axis"], dtype=float) if isinstance(c["spin_axis"], list) else None
        if a is None or a.shape != (3,) or not np.isfinite(a).all() or np.linalg.norm(a) == 0:
            raise ModelError("condense.spin_axis: expected a nonzero [x, y, z]")
        axis = a / np.linalg.norm(a)
    fixed = None
    if "fixed" in c:
        f = c["fixed"]
        if not isinstance(f, dict):
            raise ModelError("condense.fixed: expected a node set { nodes | box | sphere }")
        fixed = fe.dofs_of(_select(fe, f, "condense.fixed"))
    sets = spec.get("interface")
    if not isinstance(sets, list) or not sets:
        raise ModelError("interface: give at least one [[interface]] (the body's rheolin nodes)")
    couplings = []
    seen: dict[str, int] = {}
    for i, t in enumerate(sets):
        where = f"interface[{i}]"
        if not isinstance(t, dict):
            raise ModelError(f"{where}: expected a table")
        _unknown(t, {"name", "reference", "kind", "nodes", "box", "sphere"}, where)
        name = t.get("name")
        if not isinstance(name, str) or not name:
            raise ModelError(f"{where}.name: required")
        if name in seen:
            raise ModelError(
                f"{where}.name: {name!r} is already the name of interface[{seen[name]}]; each "
                "interface is one rheolin node and needs its own name"
            )
        seen[name] = i
        kind = t.get("kind", "average")
        if kind not in ("average", "rigid"):
            raise ModelError(f"{where}.kind: must be average or rigid, got {kind!r}")
        ref = _point(t.get("reference"), f"{where}.reference")
        couplings.append(Coupling(name, _select(fe, t, where), ref, kind=kind))
    try:
        body = condense(
            fe, None, couplings, modes=modes, cutoff_hz=cutoff, spin_axis=axis, fixed=fixed
        )
    except ModelError as exc:  # the library names its arguments; the spec names its fields
        text = str(exc)
        for arg, key in SPEC_FIELDS.items():
            if text.startswith(arg):
                raise ModelError(key + text[len(arg) :]) from None
        raise ModelError(f"fe: {text}") from None
    return body, fe


def condense_command(spec: Path = SPEC, out: Path = OUT) -> None:
    """Condense an FE body (Abaqus or Matrix Market matrices) to its interface nodes and
    fixed-interface modes (Craig-Bampton); write the .npz a model file takes."""
    if out.suffix != ".npz":
        raise ModelError(f"--out: the condensed body is an .npz file, got {str(out)!r}")
    if not out.parent.is_dir():
        raise ModelError(f"--out: no such directory {str(out.parent)!r}")
    body, fe = condense_spec(spec)
    body.save(out)
    console = Console()
    f = np.asarray(body.frequencies)
    top = f"{f.max():.4g} Hz" if f.size else "-"
    console.print(
        f"condensed {fe.n_dof:,} FE DOFs to {body.M.shape[0]} "
        f"({len(body.interface)} interface nodes x 6 + {body.n_modes} modes up to {top}; "
        f"{body.rigid_body_modes} rigid-body modes)",
        highlight=False,
    )
    console.print(f"wrote {escape(str(out))}; in a model file:", highlight=False)
    positions = ", ".join(f'"{x:.6g} {y:.6g} {z:.6g} m"' for x, y, z in body.positions)
    fixed = "" if body.spin_axis is not None else "speed_ratio = 0   # a fixed body\n"
    typer.echo(
        f'\n[[condensed_bodies]]\nname = "{out.stem}"\npath = "{out.name}"\n'
        f"positions = [{positions}]   # {', '.join(body.interface)}\n{fixed}"
    )


def register(app: typer.Typer) -> None:
    """Add ``condense`` to the ``rheolin`` application."""
    app.command("condense")(condense_command)
