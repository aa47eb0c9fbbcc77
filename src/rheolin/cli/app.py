"""Command line ``rheolin``: the terminal belongs to this module only.

Exit codes (every command; :mod:`rheolin.cli.errors` holds the contract):

* 0 -- success;
* 1 -- the computation ran but did not succeed (not converged, or the operating point is
  unstable); results are still written and say so;
* 2 -- invalid input: model file, options, output path, a problem too large for the memory
  budget, or a command whose optional part is missing; one plain line per problem naming the
  field, what was given and what is allowed; checked before any computation;
* 3 -- internal error (a bug): one short line; ``rheolin --debug ...`` shows the traceback;
* 130 -- interrupted (Ctrl-C, SIGTERM): says what was kept.
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from .. import __version__
from ..errors import ModelError
from ..harmonics.sets import TruncationWarning
from .condense import register as _register_condense
from .critical import register as _register_critical
from .errors import (
    EXIT_FAILED,
    ContractGroup,
    UserError,
    err,
    set_debug,
    set_kept,
    sigterm_as_interrupt,
)
from .frf import register as _register_frf
from .modes import register as _register_modes
from .report import parse_speed, parse_speeds, print_summary
from .ross import register as _register_ross

app = typer.Typer(
    cls=ContractGroup,
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="rheolin: periodic steady state and stability of rotating transmissions. "
    "Exit codes: 0 success, 1 not converged or unstable, 2 invalid input, "
    "3 internal error, 130 interrupted.",
)
console = Console(emoji=False, highlight=False)

#: Files ``run`` and ``campbell`` write into their output directory (an earlier run's are
#: replaced as a set).
RUN_FILES = {
    "results.nc",
    "summary.json",
    "orbits.png",
    "spectrum.png",
    "convergence.png",
    "bearing_forces.png",
}
CAMPBELL_FILES = {"campbell.nc", "campbell.png", "stability_map.nc"}

MODEL = typer.Argument(..., help="Model file (TOML, see docs/model-format.md).")
OUT = typer.Option(None, "--out", "-o", help="Output directory (created).")
METHOD = typer.Option("auto", help="Solver: auto or any registered method (see --help of run).")
HARMONICS = typer.Option(
    None, "--harmonics", help="Closure order of the harmonic set (default: the file's, else 2)."
)
MAX_ORDER = typer.Option(
    None,
    "--max-order",
    help="Frequency cut-off in orders of the input speed (default: the file's, else none).",
)
STABILITY = typer.Option(
    "auto", help="Floquet check: auto (small models only), on, off.", case_sensitive=False
)


def _fail(message: str) -> UserError:
    """An invalid option: raised, the contract prints it plainly and exits 2."""
    return UserError(message)


class _Notes:
    """Collect the warnings rheolin raises about a run (e.g. a truncated harmonic set), once
    each, for the console and the JSON summary."""

    def __init__(self) -> None:
        self.messages: list[str] = []
        self._catch = warnings.catch_warnings(record=True)

    def __enter__(self) -> _Notes:
        self._caught = self._catch.__enter__()
        warnings.simplefilter("always", TruncationWarning)
        return self

    def __exit__(self, *exc: Any) -> None:
        self._catch.__exit__(*exc)
        for w in self._caught:
            if issubclass(w.category, TruncationWarning):
                if str(w.message) not in self.messages:
                    self.messages.append(str(w.message))
            else:
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)

    def show(self) -> None:
        for m in self.messages:
            err.print(f"warning: {m}", markup=False, highlight=False, soft_wrap=True)


def _load(path: Path) -> Any:
    from ..io import read_model

    return read_model(path)


def _options(
    lm: Any,
    method: str,
    harmonics: int | None,
    max_order: float | None,
    stability: str,
    rtol: float = 1e-10,
) -> dict[str, Any]:
    from ..solvers import METHODS

    allowed = ["auto", *sorted(METHODS)]
    if method not in allowed:
        raise _fail(f"--method: must be one of {allowed}, got {method!r}")
    if harmonics is not None and harmonics < 0:
        raise _fail(f"--harmonics: must be >= 0, got {harmonics}")
    if max_order is not None and not (np.isfinite(max_order) and max_order > 0):
        raise _fail(f"--max-order: must be a finite number > 0, got {max_order}")
    if not (np.isfinite(rtol) and 0.0 < rtol < 0.1):
        raise _fail(f"--rtol: must be a number in (0, 0.1), got {rtol}")
    h = lm.spec.harmonics
    return dict(
        method=method,
        order=h.order if harmonics is None else harmonics,
        max_order=h.max_order if max_order is None else max_order,
        stability=_stability_flag(stability),
        rtol=float(rtol),
    )


def _stability_flag(stability: str) -> bool | None:
    flags = {"auto": None, "on": True, "off": False}
    if stability.lower() not in flags:
        raise _fail(f"--stability: must be auto, on or off, got {stability!r}")
    return flags[stability.lower()]


def _out_dir(out: Path | None, default: str) -> Path:
    """The output directory, refused before any computation when it cannot be written."""
    from ..io.outdir import check_output_dir

    return check_output_dir(Path(out) if out is not None else Path(default), "--out")


def _preflight(
    lm: Any, speeds: Any, order: int | None, max_order: float | None, needs_load: bool = True
) -> Any:
    """Physical admissibility and sizes against the memory budget, before any work."""
    from ..io.preflight import preflight

    return preflight(lm, speeds, order=order, max_order=max_order, needs_load=needs_load)


VARY = typer.Option(
    [],
    "--vary",
    help="Vary a model parameter: 'PATH=start:stop:count unit' or 'PATH=v1,v2 unit', e.g. "
    "'bearings.input_A.stiffness=1e8:4e8:7 N/m' (repeat for a grid; docs/studies.md).",
)
DEMO_OUT = typer.Option(Path("demo_results"), help="Output directory.")
EXAMPLE_OUT = typer.Option(
    None, "--out", "-o", help="Write the example's files into this directory."
)


RTOL = typer.Option(
    1e-10,
    "--rtol",
    help="Convergence criterion: backward error ||f - A q|| / (||A|| ||q|| + ||f||) "
    "(docs/solvers.md), in (0, 0.1).",
)


@app.callback()
def _root(
    debug: bool = typer.Option(
        False, "--debug", help="Show the traceback of an internal error (exit code 3)."
    ),
) -> None:
    """rheolin: periodic steady state and stability of rotating transmissions."""
    set_debug(debug)


@app.command()
def version() -> None:
    """Print the version."""
    console.print(__version__)


@app.command()
def validate(model: Path = MODEL) -> None:
    """Check a model file; exit 0 if valid, 2 with the field paths of every problem if not."""
    lm = _load(model)
    m = lm.model
    info = _preflight(lm, None, None, None, needs_load=False)
    console.print(
        f"{model}: valid: {len(m.bodies)} bodies, {len(m.joints)} bearings/couplings, "
        f"{len(m.meshes)} gear meshes, {len(m.forces)} forces; w1 = "
        f"{m.speed_plan().base} x input speed; {info.describe()}",
        markup=False,
    )
    if m.preloaded:  # the static equilibrium must exist (at the file's speed, if it has one)
        speed = lm.spec.model.speed or 1.0
        try:
            op = m.operating_point(speed)
        except ModelError as exc:
            raise _fail(f"{model}: {exc}") from None
        peak, (body, node) = op.max_displacement()
        console.print(
            f"preloaded: {len(m.rolling)} rolling bearings, {len(m.torques)} torques, "
            f"{sum(g.get('load_law') is not None for g in m.meshes.values())} load-dependent "
            f"meshes; static equilibrium found ({op.iterations} Newton iterations; largest "
            f"deflection {peak * 1e6:.3g} um at {body} node {node})",
            markup=False,
        )


@app.command()
def example(
    name: str = typer.Argument("gearbox", help="Example name."),
    out: Path | None = EXAMPLE_OUT,
) -> None:
    """Write a built-in example model file to stdout (rheolin example gearbox > model.toml), or
    its files into --out; gearbox-housing builds its FE housing (scikit-fem) into --out."""
    from ..data import EXAMPLES, example_text

    built = {"gearbox-housing": "the gearbox in a flexible FE housing (needs --out, scikit-fem)"}
    if name not in EXAMPLES and name not in built:
        listing = ", ".join(f"{k} ({v})" for k, v in {**EXAMPLES, **built}.items())
        raise _fail(f"no example named {name!r}; examples: {listing}")
    if name in built:
        if out is None:
            raise _fail(f"--out: the {name} example writes two files; give a directory")
        from ..fe.gearbox_housing import build

        directory = _out_dir(out, str(out))
        path = build(directory)
        console.print(
            f"wrote {escape(str(path))} and {escape(str(directory / 'housing.npz'))}; "
            f"run: rheolin run {escape(str(path))}",
            highlight=False,
        )
        return
    if out is None:
        sys.stdout.write(example_text(name))
        return
    directory = _out_dir(out, str(out))
    from ..io.atomic import atomic_write

    with atomic_write(directory / f"{name}.toml") as tmp:
        tmp.write_text(example_text(name))
    console.print(f"wrote {escape(str(directory / f'{name}.toml'))}", highlight=False)


@app.command()
def run(
    model: Path = MODEL,
    speed: str = typer.Option(None, help="Input speed, e.g. 3000rpm (default: the file's)."),
    out: Path = OUT,
    method: str = METHOD,
    harmonics: int = HARMONICS,
    max_order: float = MAX_ORDER,
    stability: str = STABILITY,
    rtol: float = RTOL,
    nodes: str = typer.Option(None, help="Orbit/spectrum nodes, e.g. input:3,output:6."),
    plots: bool = typer.Option(True, help="Write PNG plots."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
) -> None:
    """Solve one operating point; write DIR/results.nc, DIR/summary.json and plots."""
    from ..io.outdir import staged_output
    from ..results import point_dataset, solve_point, summarize, write_dataset, write_summary
    from ..results.schema import point_verdict

    lm = _load(model)
    opts = _options(lm, method, harmonics, max_order, stability, rtol)
    w = parse_speed(speed) if speed is not None else lm.spec.model.speed
    if w is None:
        raise _fail("--speed: required (the model file has no model.speed); e.g. --speed 3000rpm")
    node_list = None
    if nodes:
        node_list = [x.strip() for x in nodes.split(",") if x.strip()]
        bodies = lm.model.bodies.items()
        known = {f"{b}:{i}" for b, body in bodies for i in range(len(body.positions))}
        bad = [x for x in node_list if x not in known]
        if bad:
            raise _fail(f"--nodes: unknown {bad}; nodes look like {sorted(known)[0]!r}")
    out_dir = _out_dir(out, f"{model.stem}_results")
    _preflight(lm, [w], opts["order"], opts["max_order"])
    set_kept(f"nothing written; {out_dir} is unchanged")
    t0 = time.perf_counter()
    with _Notes() as notes, sigterm_as_interrupt():
        point = solve_point(lm.model, w, **opts)
    seconds = time.perf_counter() - t0  # assembly, solve and stability check
    ds = point_dataset(point, model_sha256=lm.sha256, model_name=lm.spec.model.name)
    summary = summarize(ds)
    summary["model_file"] = str(model)
    summary["warnings"] = notes.messages
    if lm.model.preloaded:  # solved about it: the static equilibrium (cached)
        summary["operating_point"] = lm.model.operating_point(w).to_dict()
    verdict = point_verdict(summary)
    with sigterm_as_interrupt(), staged_output(out_dir, RUN_FILES) as stage:
        write_dataset(ds, stage / "results.nc")
        write_summary(summary, stage / "summary.json")
        written = [stage / "results.nc", stage / "summary.json"]
        if plots:
            from ..plots import point_plots

            written += point_plots(ds, stage, node_list)
    written = [out_dir / p.name for p in written]
    set_kept(None)
    if as_json:
        sys.stdout.write(json.dumps(summary, indent=2) + "\n")
    else:
        print_summary(console, summary, seconds)
        notes.show()
    for note in verdict.notes:  # also with --json (stderr): undecided verdicts
        if note not in notes.messages:
            err.print(f"warning: {note}", markup=False, highlight=False, soft_wrap=True)
    if not as_json:
        console.print("wrote " + ", ".join(str(p) for p in written), markup=False)
    if not verdict.ok:
        raise typer.Exit(EXIT_FAILED)


@app.command()
def sweep(
    model: Path = MODEL,
    speeds: str = typer.Option(..., help="start:stop:step with unit (500:6000:50rpm) or a list."),
    out: Path = OUT,
    method: str = METHOD,
    harmonics: int = HARMONICS,
    max_order: float = MAX_ORDER,
    stability: str = STABILITY,
    rtol: float = RTOL,
    stability_map: bool = typer.Option(
        True, help="Also compute the Floquet stability map (stability_map.nc/.png, ranges refined)."
    ),
    plots: bool = typer.Option(True, help="Write the plots."),
    vary: list[str] = VARY,
    workers: int = typer.Option(
        None, help="Local worker processes (default: the cores; 1: no Dask, in this process)."
    ),
    scheduler: str = typer.Option(
        None, help="Run on an existing Dask cluster: its scheduler address (tcp://host:8786)."
    ),
    chunk_size: int = typer.Option(
        None, help="Points per task, rounded up to whole continuation blocks (default: adaptive)."
    ),
    overwrite: bool = typer.Option(
        False, help="Replace another study's checkpoint and results in the output directory."
    ),
    quantity: str = typer.Option(
        "response",
        help="Output of the parameter plots: response, bearing_force, dte, max_floquet_real.",
    ),
) -> None:
    """Solve over speeds (and parameter values, --vary) in parallel on Dask, checkpointed:
    a re-run of the same command computes only the missing points. Writes DIR/sweep.nc,
    DIR/sweep.json, plots and (with the map) DIR/stability_map.nc."""
    from ..plots.study import QUANTITIES
    from .sweep import run_sweep

    lm = _load(model)
    opts = _options(lm, method, harmonics, max_order, stability, rtol)
    w = parse_speeds(speeds)
    if workers is not None and workers < 1:
        raise _fail(f"--workers: must be >= 1, got {workers}")
    if chunk_size is not None and chunk_size < 1:
        raise _fail(f"--chunk-size: must be >= 1, got {chunk_size}")
    if quantity not in QUANTITIES:
        raise _fail(f"--quantity: must be one of {sorted(QUANTITIES)}, got {quantity!r}")
    out_dir = _out_dir(out, f"{model.stem}_sweep")
    _preflight(lm, w, opts["order"], opts["max_order"])
    settings = {
        **opts,
        "order": harmonics,  # None: the file's [harmonics] at every grid point
        "max_order": max_order,
        "stability_map": stability_map,
    }
    _show_operating_point(lm.model, float(w[0]), "the first speed, the file's parameters")
    run = dict(out=out_dir, overwrite=overwrite, workers=workers, chunk_size=chunk_size)
    code = run_sweep(console, err, model, w, vary, settings, scheduler, run, plots, quantity)
    raise typer.Exit(code)


def _show_operating_point(model: Any, speed: float, where: str) -> None:
    """Print the preloaded operating point (static equilibrium) a preloaded model is solved
    about: every speed of a sweep or Campbell diagram is linearized there."""
    if not model.preloaded:
        return
    from .report import print_operating_point

    console.print(f"[dim]operating point at {speed * 30 / np.pi:.1f} rpm ({where}):[/dim]")
    print_operating_point(console, model.operating_point(speed).to_dict())


@app.command()
def campbell(
    model: Path = MODEL,
    speeds: str = typer.Option(
        ..., help="start:stop:step with unit, e.g. 0:6000:100rpm (0: standstill)."
    ),
    out: Path = OUT,
    fmax: float = typer.Option(None, help="Plot up to this frequency [Hz] (default: auto)."),
    stability: str = STABILITY,
) -> None:
    """Campbell diagram: DIR/campbell.nc and DIR/campbell.png, critical speeds printed;
    with the Floquet stability of the full time-periodic system at every speed (as run and
    sweep: auto checks whenever it fits the memory budget)."""
    from ..io.outdir import staged_output
    from ..stability import campbell as campbell_fn

    lm = _load(model)
    w = parse_speeds(speeds, allow_zero=True)  # 0: the modes at standstill
    spinning = w[w > 0]  # what the preflight and the Floquet map look at
    flag = _stability_flag(stability)
    if fmax is not None and not (np.isfinite(fmax) and fmax > 0):
        raise _fail(f"--fmax: must be a frequency > 0 in Hz, got {fmax}")
    out_dir = _out_dir(out, f"{model.stem}_campbell")
    if spinning.size:
        _preflight(lm, spinning, None, None, needs_load=False)
    from ..plots.campbell import plot_campbell
    from ..results.dataset import write_dataset

    set_kept(f"nothing written; {out_dir} is unchanged")
    with sigterm_as_interrupt():
        with err.status("Campbell diagram"):
            result = campbell_fn(lm.model, w)
        smap, why = (
            _campbell_stability(lm.model, spinning, flag)
            if spinning.size
            else (None, "standstill only")
        )
    with sigterm_as_interrupt(), staged_output(out_dir, CAMPBELL_FILES) as stage:
        write_dataset(result.to_dataset(), stage / "campbell.nc")
        if smap is not None:
            write_dataset(smap.to_dataset(), stage / "stability_map.nc")
        plot_campbell(result, stage / "campbell.png", fmax, stability=smap)
    set_kept(None)
    written = [out_dir / "campbell.nc", out_dir / "campbell.png"]
    if smap is not None:
        written.append(out_dir / "stability_map.nc")
    if spinning.size:
        _show_operating_point(lm.model, float(spinning[0]), "the first spinning speed")
    table = Table(title=f"critical speeds of {escape(model.name)} (order-line crossings)")
    for col in ("order", "mode", "kind", "speed (rpm)", "frequency (Hz)"):
        table.add_column(col, justify="right" if "(" in col or col == "mode" else "left")
    for c in result.critical_speeds:
        table.add_row(
            escape(c.order),
            str(c.mode),
            c.kind or c.whirl,
            f"{c.speed * 30 / np.pi:.1f}",
            f"{c.frequency / (2 * np.pi):.2f}",
        )
    console.print(table if result.critical_speeds else "no order-line crossing in the speed range")
    code = 0
    if smap is None:
        console.print(f"[yellow]stability: not checked[/yellow] ({escape(why)})")
    elif not smap.ranges:
        undecided = int((~np.asarray(smap.decided, bool)).sum())
        if undecided:
            console.print(
                "stability (Floquet, full periodic system): [yellow]no unstable speed found, "
                f"but {undecided} of {len(smap.speeds)} speeds are UNDECIDED[/yellow] (the "
                "truncation could still flip their verdict; docs/stability.md)"
            )
        else:
            console.print(
                "stability (Floquet, full periodic system): [green]stable at every speed[/green]"
            )
    else:
        code = EXIT_FAILED
        for r in smap.ranges:
            console.print(
                f"[red]unstable[/red] {r.lower * 30 / np.pi:.1f}..{r.upper * 30 / np.pi:.1f} rpm: "
                f"{escape(r.label)}"
            )
    console.print("wrote " + ", ".join(str(p) for p in written), markup=False)
    raise typer.Exit(code)


def _campbell_stability(model: Any, speeds: np.ndarray, flag: bool | None) -> tuple[Any, str]:
    """The stability map over the Campbell speeds (None and why when it is not computed)."""
    if flag is False:
        return None, "--stability off"
    from ..budget import format_bytes, memory_budget
    from ..floquet import floquet_memory
    from ..stability import stability_map as map_fn
    from ..study.run import MAP_PRECISION

    kind, estimate = floquet_memory(model.assemble(float(speeds[-1])).system)
    if flag is None and estimate > memory_budget():
        return None, (
            f"the {kind} Hill problem needs an estimated {format_bytes(estimate)}, more than "
            f"the memory budget of {format_bytes(memory_budget())}"
        )
    columns = (TextColumn("{task.description}"), BarColumn(), TimeRemainingColumn())
    with Progress(*columns, console=err) as bar:
        task = bar.add_task("Floquet stability", total=len(speeds))
        smap = map_fn(
            model,
            speeds,
            refine=MAP_PRECISION,
            progress=lambda i, r: bar.update(task, advance=1),
        )
    return smap, ""


@app.command()
def demo(out: Path = DEMO_OUT) -> None:
    """The embedded gearbox: one operating point (3000 rpm) and a short sweep."""
    from ..data import example_path

    path = example_path("gearbox")
    console.rule("rheolin run (gearbox example, 3000 rpm)")
    code = _invoke(["run", str(path), "--out", str(out / "run")])
    console.rule("rheolin sweep (1500..4500 rpm)")
    code = max(
        code,
        _invoke(
            [
                "sweep",
                str(path),
                "--speeds",
                "1500:4500:500rpm",
                "--out",
                str(out / "sweep"),
            ]
        ),
    )
    raise typer.Exit(code)


_register_ross(app)
_register_condense(app)
_register_frf(app)
_register_critical(app)
_register_modes(app)


def _invoke(args: list[str]) -> int:
    code = app(args, standalone_mode=False)
    return int(code) if isinstance(code, int) else 0


def main() -> None:
    """Entry point of the ``rheolin`` script."""
    app()


if __name__ == "__main__":
    main()
