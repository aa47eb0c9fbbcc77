"""``rheolin run``: one operating point, its summary and its files."""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import typer

from .common import (
    FLOQUET_RTOL,
    HARMONICS,
    MAX_ORDER,
    METHOD,
    MODEL,
    OUT,
    RTOL,
    STABILITY,
    Notes,
    console,
    fail,
    floquet_rtol,
    load,
    output_dir,
    preflight,
    solve_options,
)
from .errors import EXIT_FAILED, err, set_kept, sigterm_as_interrupt
from .parse import parse_speed
from .progress import working
from .report import print_summary

__all__ = ["RUN_FILES", "register", "run"]

#: Files ``run`` writes into its output directory (an earlier run's are replaced as a set).
RUN_FILES = {
    "results.nc",
    "summary.json",
    "orbits.png",
    "spectrum.png",
    "convergence.png",
    "bearing_forces.png",
    "report.html",
}


def run(
    model: Path = MODEL,
    speed: str = typer.Option(None, help="Input speed, e.g. 3000rpm (default: the file's)."),
    out: Path = OUT,
    method: str = METHOD,
    harmonics: int = HARMONICS,
    max_order: float = MAX_ORDER,
    stability: str = STABILITY,
    rtol: float = RTOL,
    floquet_accuracy: float = FLOQUET_RTOL,
    nodes: str = typer.Option(None, help="Orbit/spectrum nodes, e.g. input:3,output:6."),
    plots: bool = typer.Option(True, help="Write PNG plots."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
    report: bool = typer.Option(False, "--report", help="Also write DIR/report.html."),
) -> None:
    """Solve one operating point; write DIR/results.nc, DIR/summary.json and plots."""
    from ..io.outdir import staged_output
    from ..results import point_dataset, solve_point, summarize, write_dataset, write_summary
    from ..results.schema import point_verdict

    lm = load(model)
    opts = solve_options(lm, method, harmonics, max_order, stability, rtol)
    accuracy = floquet_rtol(floquet_accuracy)
    if accuracy is not None:  # the continuation carries it to the verdict
        from ..floquet import Continuation

        opts["continuation"] = Continuation(rtol=accuracy)
    w = parse_speed(speed) if speed is not None else lm.spec.model.speed
    if w is None:
        raise fail("--speed: required (the model file has no model.speed); e.g. --speed 3000rpm")
    node_list = None
    if nodes:
        node_list = [x.strip() for x in nodes.split(",") if x.strip()]
        bodies = lm.model.bodies.items()
        known = {f"{b}:{i}" for b, body in bodies for i in range(len(body.positions))}
        bad = [x for x in node_list if x not in known]
        if bad:
            raise fail(f"--nodes: unknown {bad}; nodes look like {sorted(known)[0]!r}")
    out_dir = output_dir(out, f"{model.stem}_results")
    preflight(lm, [w], opts["order"], opts["max_order"], stability=opts["stability"])
    set_kept(f"nothing written; {out_dir} is unchanged")
    t0 = time.perf_counter()
    rpm = w * 30 / math.pi
    with Notes() as notes, sigterm_as_interrupt(), working(f"solving at {rpm:.6g} rpm"):
        point = solve_point(lm.model, w, **opts)
    seconds = time.perf_counter() - t0  # assembly, solve and stability check
    ds = point_dataset(point, model_sha256=lm.sha256, model_name=lm.spec.model.name)
    summary = summarize(ds)
    summary["model_file"] = str(model)
    summary["warnings"] = notes.messages
    if lm.model.preloaded:  # solved about it: the static equilibrium (cached)
        summary["operating_point"] = lm.model.operating_point(w).to_dict()
        for note in summary["operating_point"]["notes"]:  # a torque the drive takes
            if note not in notes.messages:
                notes.messages.append(note)
    verdict = point_verdict(summary)
    with sigterm_as_interrupt(), staged_output(out_dir, RUN_FILES) as stage:
        write_dataset(ds, stage / "results.nc")
        write_summary(summary, stage / "summary.json")
        written = [stage / "results.nc", stage / "summary.json"]
        if plots:
            from ..plots import point_plots

            written += point_plots(ds, stage, node_list)
        if report:
            from ..report import write_report

            written.append(write_report(stage, model=model, where=str(out_dir)))
    written = [out_dir / p.name for p in written]
    set_kept(f"the files in {out_dir} are complete")
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


def register(app: typer.Typer) -> None:
    """Add ``run`` to the ``rheolin`` application."""
    app.command("run")(run)
