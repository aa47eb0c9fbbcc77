"""Command line ``rheolin``: the terminal belongs to this module only.

Exit codes (every command):

* 0 -- success;
* 1 -- the computation ran but did not succeed (not converged, or the operating point is
  unstable); results are still written and say so;
* 2 -- invalid input: model file, options, or a command whose optional part is missing.
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

from . import __version__
from ._cli_report import parse_speed, parse_speeds, print_summary
from ._cli_ross import register as _register_ross
from .errors import ModelError
from .harmonics import TruncationWarning

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="rheolin: periodic steady state and stability of rotating transmissions. "
    "Exit codes: 0 success, 1 not converged or unstable, 2 invalid input.",
)
console = Console()
err = Console(stderr=True)

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


def _fail(message: str) -> typer.Exit:
    err.print(f"[red]error:[/red] {message}", highlight=False, markup=True, soft_wrap=True)
    return typer.Exit(2)


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
            err.print(f"[yellow]warning:[/yellow] {escape(m)}", highlight=False)


def _load(path: Path) -> Any:
    from .io import read_model

    try:
        return read_model(path)
    except ModelError as exc:
        raise _fail(str(exc)) from None


def _options(
    lm: Any, method: str, harmonics: int | None, max_order: float | None, stability: str
) -> dict[str, Any]:
    from .solvers import METHODS

    allowed = ["auto", *sorted(METHODS)]
    if method not in allowed:
        raise _fail(f"--method must be one of {allowed}, got {method!r}")
    if harmonics is not None and harmonics < 0:
        raise _fail(f"--harmonics must be >= 0, got {harmonics}")
    if max_order is not None and not max_order > 0:
        raise _fail(f"--max-order must be > 0, got {max_order}")
    flags = {"auto": None, "on": True, "off": False}
    if stability.lower() not in flags:
        raise _fail(f"--stability must be auto, on or off, got {stability!r}")
    h = lm.spec.harmonics
    return dict(
        method=method,
        order=h.order if harmonics is None else harmonics,
        max_order=h.max_order if max_order is None else max_order,
        stability=flags[stability.lower()],
    )


VARY = typer.Option(
    [],
    "--vary",
    help="Vary a model parameter: 'PATH=start:stop:count unit' or 'PATH=v1,v2 unit', e.g. "
    "'bearings.input_A.stiffness=1e8:4e8:7 N/m' (repeat for a grid; docs/studies.md).",
)
DEMO_OUT = typer.Option(Path("demo_results"), help="Output directory.")


@app.callback()
def _root() -> None:
    """rheolin: periodic steady state and stability of rotating transmissions."""


@app.command()
def version() -> None:
    """Print the version."""
    console.print(__version__)


@app.command()
def validate(model: Path = MODEL) -> None:
    """Check a model file; exit 0 if valid, 2 with the field paths of every problem if not."""
    lm = _load(model)
    m = lm.model
    console.print(
        f"{model}: valid: {len(m.bodies)} bodies, {len(m.joints)} bearings/couplings, "
        f"{len(m.meshes)} gear meshes, {len(m.forces)} forces; w1 = "
        f"{m.speed_plan().base} x input speed"
    )


@app.command()
def example(name: str = typer.Argument("gearbox", help="Example name.")) -> None:
    """Write a built-in example model file to stdout: rheolin example gearbox > model.toml."""
    from .data import EXAMPLES, example_text

    if name not in EXAMPLES:
        listing = ", ".join(f"{k} ({v})" for k, v in EXAMPLES.items())
        raise _fail(f"no example named {name!r}; examples: {listing}")
    sys.stdout.write(example_text(name))


@app.command()
def run(
    model: Path = MODEL,
    speed: str = typer.Option(None, help="Input speed, e.g. 3000rpm (default: the file's)."),
    out: Path = OUT,
    method: str = METHOD,
    harmonics: int = HARMONICS,
    max_order: float = MAX_ORDER,
    stability: str = STABILITY,
    nodes: str = typer.Option(None, help="Orbit/spectrum nodes, e.g. input:3,output:6."),
    plots: bool = typer.Option(True, help="Write PNG plots."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
) -> None:
    """Solve one operating point; write DIR/results.nc, DIR/summary.json and plots."""
    from .results import point_dataset, solve_point, summarize, write_dataset, write_summary

    lm = _load(model)
    opts = _options(lm, method, harmonics, max_order, stability)
    try:
        w = parse_speed(speed) if speed is not None else lm.spec.model.speed
    except ModelError as exc:
        raise _fail(str(exc)) from None
    if w is None:
        raise _fail("give --speed (the model file has no model.speed)")
    out_dir = Path(out) if out is not None else Path(f"{model.stem}_results")
    t0 = time.perf_counter()
    with _Notes() as notes:
        point = solve_point(lm.model, w, **opts)
    seconds = time.perf_counter() - t0  # assembly, solve and stability check
    ds = point_dataset(point, model_sha256=lm.sha256, model_name=lm.spec.model.name)
    node_list = None
    if nodes:
        node_list = [x.strip() for x in nodes.split(",") if x.strip()]
        bad = [x for x in node_list if x not in ds["node"].values]
        if bad:
            raise _fail(f"--nodes: unknown {bad}; nodes look like {ds['node'].values[0]!r}")
    write_dataset(ds, out_dir / "results.nc")
    summary = summarize(ds)
    summary["model_file"] = str(model)
    summary["warnings"] = notes.messages
    write_summary(summary, out_dir / "summary.json")
    written = [out_dir / "results.nc", out_dir / "summary.json"]
    if plots:
        from .plots import point_plots

        written += point_plots(ds, out_dir, node_list)
    if as_json:
        sys.stdout.write(json.dumps(summary, indent=2) + "\n")
    else:
        print_summary(console, summary, seconds)
        notes.show()
        console.print("wrote " + ", ".join(str(p) for p in written))
    if not point.solution.success:
        raise typer.Exit(1)


@app.command()
def sweep(
    model: Path = MODEL,
    speeds: str = typer.Option(..., help="start:stop:step with unit (500:6000:50rpm) or a list."),
    out: Path = OUT,
    method: str = METHOD,
    harmonics: int = HARMONICS,
    max_order: float = MAX_ORDER,
    stability: str = STABILITY,
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
    chunk_size: int = typer.Option(None, help="Points per task (default: adaptive)."),
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
    from ._cli_study import run_sweep
    from .plots.study import QUANTITIES

    lm = _load(model)
    opts = _options(lm, method, harmonics, max_order, stability)
    try:
        w = parse_speeds(speeds)
    except ModelError as exc:
        raise _fail(str(exc)) from None
    if workers is not None and workers < 1:
        raise _fail(f"--workers must be >= 1, got {workers}")
    if chunk_size is not None and chunk_size < 1:
        raise _fail(f"--chunk-size must be >= 1, got {chunk_size}")
    if quantity not in QUANTITIES:
        raise _fail(f"--quantity must be one of {sorted(QUANTITIES)}, got {quantity!r}")
    settings = {
        **opts,
        "order": harmonics,  # None: the file's [harmonics] at every grid point
        "max_order": max_order,
        "stability_map": stability_map,
    }
    out_dir = Path(out) if out is not None else Path(f"{model.stem}_sweep")
    run = dict(out=out_dir, overwrite=overwrite, workers=workers, chunk_size=chunk_size)
    code = run_sweep(console, err, model, w, vary, settings, scheduler, run, plots, quantity)
    raise typer.Exit(code)


@app.command()
def campbell(
    model: Path = MODEL,
    speeds: str = typer.Option(..., help="start:stop:step with unit, e.g. 100:6000:100rpm."),
    out: Path = OUT,
    fmax: float = typer.Option(None, help="Plot up to this frequency [Hz] (default: auto)."),
    stability: str = STABILITY,
) -> None:
    """Campbell diagram: DIR/campbell.nc and DIR/campbell.png, critical speeds printed;
    with the Floquet stability of the full time-periodic system at every speed (as run and
    sweep: auto checks whenever it fits the memory budget)."""
    from .stability import campbell as campbell_fn

    lm = _load(model)
    try:
        w = parse_speeds(speeds)
    except ModelError as exc:
        raise _fail(str(exc)) from None
    flags = {"auto": None, "on": True, "off": False}
    if stability.lower() not in flags:
        raise _fail(f"--stability must be auto, on or off, got {stability!r}")
    from .plots.campbell import plot_campbell
    from .results.dataset import write_dataset

    out_dir = Path(out) if out is not None else Path(f"{model.stem}_campbell")
    with err.status("Campbell diagram"):
        result = campbell_fn(lm.model, w)
    smap, why = _campbell_stability(lm.model, w, flags[stability.lower()])
    write_dataset(result.to_dataset(), out_dir / "campbell.nc")
    written = [out_dir / "campbell.nc", out_dir / "campbell.png"]
    if smap is not None:
        write_dataset(smap.to_dataset(), out_dir / "stability_map.nc")
        written.append(out_dir / "stability_map.nc")
    plot_campbell(result, out_dir / "campbell.png", fmax, stability=smap)
    table = Table(title=f"critical speeds of {model.name} (order-line crossings)")
    for col in ("order", "mode", "whirl", "speed (rpm)", "frequency (Hz)"):
        table.add_column(col, justify="right" if "(" in col or col == "mode" else "left")
    for c in result.critical_speeds:
        table.add_row(
            c.order,
            str(c.mode),
            c.whirl,
            f"{c.speed * 30 / np.pi:.1f}",
            f"{c.frequency / (2 * np.pi):.2f}",
        )
    console.print(table if result.critical_speeds else "no order-line crossing in the speed range")
    if smap is None:
        console.print(f"[yellow]stability: not checked[/yellow] ({why})")
    elif not smap.ranges:
        undecided = int((~np.asarray(smap.decided, bool)).sum())
        note = f" ({undecided} speeds undecided)" if undecided else ""
        console.print(
            f"stability (Floquet, full periodic system): [green]stable at every speed[/green]{note}"
        )
    else:
        for r in smap.ranges:
            console.print(
                f"[red]unstable[/red] {r.lower * 30 / np.pi:.1f}..{r.upper * 30 / np.pi:.1f} rpm: "
                f"{escape(r.label)}"
            )
    console.print("wrote " + ", ".join(str(p) for p in written))


def _campbell_stability(model: Any, speeds: np.ndarray, flag: bool | None) -> tuple[Any, str]:
    """The stability map over the Campbell speeds (None and why when it is not computed)."""
    if flag is False:
        return None, "--stability off"
    from .budget import format_bytes, memory_budget
    from .floquet import floquet_memory
    from .stability import stability_map as map_fn
    from .study.run import MAP_PRECISION

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
    from .data import example_path

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
                "--no-stability-map",
            ]
        ),
    )
    raise typer.Exit(code)


_register_ross(app)


def _invoke(args: list[str]) -> int:
    try:
        app(args, standalone_mode=False)
    except typer.Exit as exc:
        return int(exc.exit_code)
    return 0


def main() -> None:
    """Entry point of the ``rheolin`` script."""
    app()


if __name__ == "__main__":
    main()
