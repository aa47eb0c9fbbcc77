"""``rheolin campbell``: the Campbell diagram, its critical speeds and the Floquet stability
map over the same speeds."""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import typer
from rich.markup import escape
from rich.table import Table

from .. import __version__
from .common import (
    FLOQUET_RTOL,
    MODEL,
    OUT,
    STABILITY,
    console,
    fail,
    floquet_rtol,
    load,
    output_dir,
    preflight,
    show_operating_point,
    stability_flag,
)
from .errors import EXIT_FAILED, set_kept, sigterm_as_interrupt
from .parse import parse_speeds
from .progress import counted

__all__ = ["CAMPBELL_FILES", "campbell", "register"]

#: Files ``campbell`` writes into its output directory (an earlier run's are replaced as a set).
CAMPBELL_FILES = {"campbell.nc", "campbell.png", "stability_map.nc", "report.html"}

#: From this many spinning speeds on, the stability check runs on worker processes by
#: default (starting them costs a few seconds).
PARALLEL_SPEEDS = 8


def campbell(
    model: Path = MODEL,
    speeds: str = typer.Option(
        ..., help="start:stop:step with unit, e.g. 0:6000:100rpm (0: standstill)."
    ),
    out: Path = OUT,
    fmax: float = typer.Option(None, help="Plot up to this frequency [Hz] (default: auto)."),
    stability: str = STABILITY,
    floquet_accuracy: float = FLOQUET_RTOL,
    report: bool = typer.Option(False, "--report", help="Also write DIR/report.html."),
    workers: int = typer.Option(
        None,
        help="Worker processes for the stability check (default: the cores, from "
        f"{PARALLEL_SPEEDS} spinning speeds on; 1: in this process). The diagram is computed "
        "meanwhile.",
    ),
) -> None:
    """Campbell diagram: DIR/campbell.nc and DIR/campbell.png, critical speeds printed;
    with the Floquet stability of the full time-periodic system at every speed (as run and
    sweep: auto checks whenever it fits the memory budget)."""
    from ..io.outdir import staged_output
    from ..stability import campbell as campbell_fn

    lm = load(model)
    w = parse_speeds(speeds, allow_zero=True)  # 0: the modes at standstill
    spinning = w[w > 0]  # what the preflight looks at (the map's standstill is frozen)
    flag = stability_flag(stability)
    accuracy = floquet_rtol(floquet_accuracy)
    if fmax is not None and not (np.isfinite(fmax) and fmax > 0):
        raise fail(f"--fmax: must be a frequency > 0 in Hz, got {fmax}")
    if workers is not None and workers < 1:
        raise fail(f"--workers: must be >= 1, got {workers}")
    out_dir = output_dir(out, f"{model.stem}_campbell")
    if spinning.size:
        preflight(lm, spinning, None, None, needs_load=False)
    from ..results.dataset import write_dataset

    set_kept(f"nothing written; {out_dir} is unchanged")
    with sigterm_as_interrupt():

        def diagram() -> Any:
            with counted("Campbell diagram", w.size, "speeds") as step:
                out = campbell_fn(lm.model, w, progress=step)
            # Matplotlib (a second to load) while the stability check's workers still run
            import rheolin.plots.campbell  # noqa: F401

            return out

        if spinning.size:
            result, (smap, why) = _with_stability(lm.model, w, flag, accuracy, workers, diagram)
        else:
            result, smap, why = diagram(), None, "standstill only"
    from ..plots.campbell import plot_campbell  # loaded by diagram()

    with sigterm_as_interrupt(), staged_output(out_dir, CAMPBELL_FILES) as stage:
        ds = result.to_dataset()
        ds.attrs.update(model_file=str(model), model_sha256=lm.sha256, rheolin_version=__version__)
        write_dataset(ds, stage / "campbell.nc")
        if smap is not None:
            write_dataset(smap.to_dataset(), stage / "stability_map.nc")
        plot_campbell(result, stage / "campbell.png", fmax, stability=smap)
        if report:
            from ..report import write_report

            write_report(stage, model=model, where=str(out_dir))
    set_kept(f"the files in {out_dir} are complete")
    written = [out_dir / "campbell.nc", out_dir / "campbell.png"]
    if report:
        written.append(out_dir / "report.html")
    if smap is not None:
        written.append(out_dir / "stability_map.nc")
    if spinning.size:
        show_operating_point(lm.model, float(spinning[0]), "the first spinning speed")
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
    else:
        late = np.asarray(smap.speeds)[np.asarray(smap.undecided, bool)] * 30 / np.pi
        if not smap.ranges and not late.size:
            console.print(
                "stability (Floquet, full periodic system): [green]stable at every speed[/green]"
            )
        for r in smap.ranges:
            console.print(
                f"[red]unstable[/red] {_bound(r.lower, r.lower_uncertainty)}.."
                f"{_bound(r.upper, r.upper_uncertainty)} rpm: {escape(r.label)}"
            )
        if late.size:  # neither stable nor unstable: exit 1 as for an unstable range
            shown = ", ".join(f"{x:.6g}" for x in late)
            console.print(
                f"stability: [yellow]{late.size} speed{'s' if late.size > 1 else ''} undecided: "
                f"{shown} rpm[/yellow] (the Floquet truncation could still flip their verdict; "
                "docs/stability.md)"
            )
        for w, why in smap.info.get("failed", {}).items():
            console.print(
                f"stability at {w * 30 / np.pi:.6g} rpm: [yellow]no verdict[/yellow] "
                f"({escape(why)})"
            )
        if smap.ranges or late.size:
            code = EXIT_FAILED
    console.print("wrote " + ", ".join(str(p) for p in written), markup=False)
    raise typer.Exit(code)


def _bound(w: float, unc: float) -> str:
    """A range bound [rad/s] in rpm, with its uncertainty when it is finite."""
    rpm = w * 30 / np.pi
    return f"{rpm:.1f}" if not np.isfinite(unc) else f"{rpm:.2f} (+-{unc * 30 / np.pi:.2g})"


def _with_stability(
    model: Any,
    speeds: np.ndarray,
    flag: bool | None,
    accuracy: float | None,
    workers: int | None,
    diagram: Callable[[], Any],
) -> tuple[Any, tuple[Any, str]]:
    """The diagram and the stability map over the Campbell speeds (None and why when it is
    not computed). With more than one worker the map's blocks run on local worker processes
    while this process computes the diagram."""
    if flag is False:
        return diagram(), (None, "--stability off")
    from ..budget import format_bytes, memory_budget
    from ..floquet import floquet_memory
    from ..study.executor import cores

    kind, estimate = floquet_memory(model.assemble(float(speeds[-1])).system)
    budget = memory_budget()
    if flag is None and estimate > budget:
        return diagram(), (
            None,
            f"the {kind} Hill problem needs an estimated {format_bytes(estimate)}, more than "
            f"the memory budget of {format_bytes(budget)}",
        )
    spinning = int(np.sum(speeds > 0))
    n = workers if workers is not None else (cores() if spinning >= PARALLEL_SPEEDS else 1)
    n = max(1, min(n, spinning, int(budget // max(estimate, 1))))
    if n == 1:
        result = diagram()
        with counted("Floquet stability", len(speeds), "speeds") as step:
            return result, _stability_map(model, speeds, flag, accuracy, lambda i: step(i + 1))
    from ..study.executor import local_workers

    done: list[int] = []
    box: dict[str, Any] = {}

    def check() -> None:
        try:
            box["map"] = _stability_map(
                model, speeds, flag, accuracy, lambda i: done.append(i), client=client
            )
        except BaseException as exc:  # raised again in this thread
            box["error"] = exc

    # the workers are started here, before the check's thread (forked copies of this process
    # where that is safe: see local_workers)
    with local_workers(n) as client:
        thread = threading.Thread(target=check, name="rheolin-stability", daemon=True)
        thread.start()
        result = diagram()
        with counted("Floquet stability", len(speeds), "speeds") as step:
            while thread.is_alive():
                thread.join(0.2)
                step(len(done))
    if "error" in box:
        raise box["error"]
    return result, box["map"]


def _stability_map(
    model: Any,
    speeds: np.ndarray,
    flag: bool | None,
    accuracy: float | None,
    progress: Callable[[int], None],
    client: Any = None,
) -> tuple[Any, str]:
    """The stability map over the Campbell speeds (on ``client``'s workers when given)."""
    from ..stability import stability_map as map_fn
    from ..study.run import MAP_PRECISION
    from ..system.rigid_modes import FreeBodyError

    try:
        smap = map_fn(
            model,
            speeds,
            refine=MAP_PRECISION,
            progress=lambda i, r: progress(i),
            rtol=accuracy,
            client=client,
        )
    except FreeBodyError as exc:  # a free body has modes, but no operating point
        if flag:
            raise
        return None, str(exc)
    return smap, ""


def register(app: typer.Typer) -> None:
    """Add ``campbell`` to the ``rheolin`` application."""
    app.command("campbell")(campbell)
