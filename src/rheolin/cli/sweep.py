"""``rheolin sweep``: the command, the progress bar over the whole study and the summary."""

from __future__ import annotations

import contextlib
import functools
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from .common import (
    FLOQUET_RTOL,
    HARMONICS,
    MAX_ORDER,
    METHOD,
    MODEL,
    OUT,
    RTOL,
    STABILITY,
    console,
    fail,
    floquet_rtol,
    load,
    output_dir,
    preflight,
    show_operating_point,
    solve_options,
)
from .errors import (
    EXIT_FAILED,
    EXIT_INPUT,
    EXIT_INTERRUPTED,
    err,
    plain_error,
    sigterm_as_interrupt,
)
from .parse import parse_speeds
from .progress import INTERVAL, LogLines

__all__ = ["StudyBar", "map_counts", "print_study_summary", "register", "run_sweep", "sweep"]

RPM = 30 / np.pi

VARY = typer.Option(
    [],
    "--vary",
    help="Vary a model parameter: 'PATH=start:stop:count unit' or 'PATH=v1,v2 unit', e.g. "
    "'bearings.input_A.stiffness=1e8:4e8:7 N/m' (repeat for a grid; docs/studies.md).",
)


def sweep(
    model: Path = MODEL,
    speeds: str = typer.Option(..., help="start:stop:step with unit (500:6000:50rpm) or a list."),
    out: Path = OUT,
    method: str = METHOD,
    harmonics: int = HARMONICS,
    max_order: float = MAX_ORDER,
    stability: str = STABILITY,
    rtol: float = RTOL,
    floquet_accuracy: float = FLOQUET_RTOL,
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
    refine_peaks: bool = typer.Option(
        False,
        "--refine-peaks",
        help="Add speeds around resonance peaks with fewer than 5 speeds in their half-power "
        "band, and run again (up to twice), so that their amplification factors are resolved.",
    ),
    report: bool = typer.Option(False, "--report", help="Also write DIR/report.html."),
) -> None:
    """Solve over speeds (and parameter values, --vary) in parallel on Dask, checkpointed:
    a re-run of the same command computes only the missing points. Writes DIR/sweep.nc,
    DIR/sweep.json, plots and (with the map) DIR/stability_map.nc."""
    from ..plots.study import QUANTITIES

    lm = load(model)
    opts = solve_options(lm, method, harmonics, max_order, stability, rtol)
    w = parse_speeds(speeds)
    if workers is not None and workers < 1:
        raise fail(f"--workers: must be >= 1, got {workers}")
    if chunk_size is not None and chunk_size < 1:
        raise fail(f"--chunk-size: must be >= 1, got {chunk_size}")
    if quantity not in QUANTITIES:
        raise fail(f"--quantity: must be one of {sorted(QUANTITIES)}, got {quantity!r}")
    if refine_peaks and vary:
        raise fail("--refine-peaks: for a speed sweep only (resonances are not sought with --vary)")
    out_dir = output_dir(out, f"{model.stem}_sweep")
    preflight(lm, w, opts["order"], opts["max_order"])
    settings = {
        **opts,
        "order": harmonics,  # None: the file's [harmonics] at every grid point
        "max_order": max_order,
        "stability_map": stability_map,
        "floquet_rtol": floquet_rtol(floquet_accuracy),
    }
    show_operating_point(lm.model, float(w[0]), "the first speed, the file's parameters")
    run = dict(out=out_dir, overwrite=overwrite, workers=workers, chunk_size=chunk_size)
    code = run_sweep(console, err, model, w, vary, settings, scheduler, run, plots, quantity)
    for attempt in range(2 if refine_peaks else 0):
        from .peaks import refined_speeds

        more = refined_speeds(out_dir, w) if code in (0, EXIT_FAILED) else None
        if more is None:
            break
        console.print(
            f"refining resonance peaks (pass {attempt + 1}): {more.size - w.size} speeds added",
            highlight=False,
        )
        w = more
        run = {**run, "overwrite": True}  # this sweep's own checkpoint, with other speeds
        code = run_sweep(console, err, model, w, vary, settings, scheduler, run, plots, quantity)
    if report and code in (0, EXIT_FAILED):
        from .html_report import write_report_for

        write_report_for(out_dir, model)
    elif (out_dir / "report.html").is_file():  # an earlier run's: it describes other results
        (out_dir / "report.html").unlink()
    raise typer.Exit(code)


def run_sweep(
    console: Console,
    err: Console,
    model: Path,
    speeds: np.ndarray,
    vary: Sequence[str],
    settings: dict[str, Any],
    scheduler: str | None,
    run: dict[str, Any],
    plots: bool,
    quantity: str,
) -> int:
    """Run the study of ``rheolin sweep``; returns the exit code (0, 1, 2, 130). ``run`` holds
    the keywords of :func:`rheolin.study.run_study` (``out``, ``workers``, ...)."""
    from ..errors import ModelError
    from ..study import ParameterError, Settings, StudyInterrupted, StudySpec, run_study
    from ..study.files import write_results

    def refuse(message: str) -> int:
        plain_error(message)
        return EXIT_INPUT

    try:
        spec = StudySpec.create(model, speeds, list(vary), Settings(**settings))
    except ParameterError as exc:
        return refuse(f"--vary {exc}")
    except ModelError as exc:
        return refuse(str(exc))
    write = functools.partial(write_results, plots=plots, quantity=quantity)
    try:
        # local workers are started before the bar's thread (forked where that is safe)
        with _client(scheduler, run.get("workers")) as client, sigterm_as_interrupt(), \
                StudyBar(err, spec) as bar:  # fmt: skip
            result = run_study(spec, client=client, progress=bar, write=write, **run)
    except StudyInterrupted as exc:
        err.print(
            f"interrupted: {exc.done} of {exc.total} points are done and kept in "
            f"{Path(run['out']) / 'checkpoint'}; run the same command again to resume",
            highlight=False,
            soft_wrap=True,
        )
        return EXIT_INTERRUPTED
    except ModelError as exc:  # another study in the directory, a busy directory, --scheduler
        return refuse(str(exc))
    print_study_summary(console, err, result)
    # exit 1: a point not converged, an unstable range, or an undecided verdict (its
    # stability could go either way: not a pass); docs/cli.md
    converged = bool((result.dataset["success"] == 1).all())
    clean = converged and not map_counts(result)["ranges"] and not undecided_points(result)
    return 0 if clean else EXIT_FAILED


@contextlib.contextmanager
def _client(address: str | None, workers: int | None = 1) -> Iterator[Any]:
    """A client of an existing cluster (not closed with the study's end); without one, the
    local workers of ``workers`` > 1 (None: a core each;
    :func:`~rheolin.study.executor.local_workers`), or None."""
    if address is None:
        if workers is not None and workers <= 1:
            yield None
            return
        from ..study.executor import local_workers

        with local_workers(workers) as ex:
            yield ex
        return
    from distributed import Client

    from ..errors import ModelError

    try:
        client = Client(address, timeout="10s")
    except (OSError, ValueError) as exc:
        raise ModelError(f"--scheduler {address}: cannot connect: {exc}") from None
    try:
        yield client
    finally:
        client.close()


class StudyBar:
    """One rich progress bar with an ETA over every point (and then every stability map
    being refined); failed points are printed above it as they are reported."""

    def __init__(self, console: Console, spec: Any) -> None:
        self.console = console
        self.spec = spec
        self.progress = Progress(
            TextColumn("{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("elapsed"),
            TimeElapsedColumn(),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            console=console,
        )
        self.task: Any = None
        self.announced = False
        self.lines: LogLines | None = None

    def __enter__(self) -> StudyBar:
        self.progress.__enter__()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.progress.__exit__(*exc)

    def __call__(self, event: Any) -> None:
        if self.task is None:
            if event.resumed:
                self.console.print(
                    f"resumed: {event.resumed} of {event.total} points already done",
                    highlight=False,
                )
            self.task = self.progress.add_task("points", total=event.total, completed=event.done)
        for point, message in event.failures:
            self.console.print(
                f"[red]failed:[/red] {escape(self.where(point))}: {escape(message)}",
                highlight=False,
            )
        what = "stability maps" if event.phase == "maps" else "points"
        failed = f" ({event.failed} failed)" if event.failed else ""
        self.progress.update(
            self.task, completed=event.done, total=event.total, description=what + failed
        )
        if not self.console.is_terminal:  # a log: rich draws no bar there
            if self.lines is None or self.lines.what != what:
                self.lines = LogLines(self.console, what, event.total, "", INTERVAL, time.monotonic)
            self.lines.update(event.done)

    def where(self, point: int) -> str:
        return self.where_point(self.spec, point)

    @staticmethod
    def where_point(spec: Any, point: int) -> str:
        """``"900 rpm"`` (with the parameter values of a study) for a point."""
        rpm = float(spec.speeds[spec.speed_of(point)]) * RPM
        extra = spec.describe(spec.combo_of(point))
        return f"{rpm:.6g} rpm" + (f", {extra}" if extra else "")


def map_counts(result: Any) -> dict[str, int]:
    """Over every stability map of a study: speeds, unstable and undecided speeds, speeds
    whose truncation did not converge, unstable ranges."""
    out = dict(speeds=0, unstable=0, undecided=0, unconverged=0, ranges=0)
    for smap in result.maps.values():
        n = int(np.size(smap.speeds))
        undecided = np.asarray(smap.undecided, bool)
        out["speeds"] += n
        out["unstable"] += int((~np.asarray(smap.stable, bool) & ~undecided).sum())
        out["undecided"] += int(undecided.sum())
        out["unconverged"] += int((~np.asarray(smap.converged, bool)).sum())
        out["ranges"] += len(smap.ranges)
    return out


def undecided_points(result: Any) -> list[str]:
    """Where the verdict is undecided: each point flagged so (``stable = -2``), or, with the
    stability check off, each speed of a map whose verdict is; as ``"900 rpm"`` (with the
    parameter values of a study)."""
    spec = result.spec
    flags = np.asarray(result.dataset["stable"].values).reshape(-1)
    where = [StudyBar.where_point(spec, int(p)) for p in np.flatnonzero(flags == -2)]
    if where or not (flags == -1).any():
        return where
    for combo, smap in sorted(result.maps.items()):
        extra = spec.describe(combo)
        for w in np.asarray(smap.speeds)[np.asarray(smap.undecided, bool)]:
            where.append(f"{float(w) * RPM:.6g} rpm" + (f", {extra}" if extra else ""))
    return where


def print_study_summary(console: Console, err: Console, result: Any) -> None:
    """Counts, unstable ranges and the files written (warnings to ``err``)."""
    ds, spec = result.dataset, result.spec
    n = spec.n_points
    failed = int((ds["status"] < 0).sum())
    unsuccessful = int((ds["success"] == 0).sum())
    unstable = int((ds["stable"] == 0).sum())
    undecided = int((ds["stable"] == -2).sum())
    unchecked = int((ds["stable"] == -1).sum())
    grid = " x ".join(str(len(p.values)) for p in spec.parameters)
    size = f"{spec.speeds.size} speeds" + (f" x {grid} parameter values" if grid else "")
    ranges = []
    for combo, smap in sorted(result.maps.items()):
        at = spec.describe(combo)
        for r in smap.ranges:
            where = f" at {at}" if at else ""
            ranges.append(
                f"{r.lower * RPM:.1f}..{r.upper * RPM:.1f}{where} ({r.label or r.mechanism})"
            )
    counts = map_counts(result)
    if unchecked and counts["speeds"]:  # --stability off: the map's verdicts are the verdicts
        verdict = (
            f"stability (from the map): {counts['unstable']} unstable, "
            f"{counts['undecided']} undecided of {counts['speeds']} speeds"
        )
    else:
        verdict = f"stability: {unstable} unstable, {undecided} undecided, {unchecked} not checked"
    console.print(
        f"{size} = {n} points ({result.resumed} from the checkpoint, {result.computed} "
        f"computed now): {n - unsuccessful} converged, {unsuccessful} not successful"
        f"{f' ({failed} failed with an error)' if failed else ''}; {verdict}",
        markup=False,
        highlight=False,
        soft_wrap=True,
    )
    late = undecided_points(result)
    if late:
        more = f" and {len(late) - 12} more" if len(late) > 12 else ""
        shown = _one_unit(", ".join(late[:12])) + more
        console.print(
            f"{len(late)} speed{'s' if len(late) > 1 else ''} undecided: {shown} (the Floquet "
            "truncation could still flip their verdicts; sweep.json `stability`, "
            "docs/stability.md)",
            markup=False,
            highlight=False,
            soft_wrap=True,
        )
    if result.maps:
        console.print(
            "stability map unstable ranges (rpm): " + ("; ".join(ranges) or "none"), markup=False
        )
        # a truncation that has not converged for every exponent is normal on a coarse
        # lattice (heavily damped high modes, exponents confirmed on a finer one): only an
        # undecided verdict is a warning
        if counts["undecided"]:
            err.print(
                f"warning: stability map: the verdict is undecided at {counts['undecided']} "
                f"of {counts['speeds']} speeds (the Floquet truncation did not converge for "
                f"every exponent at {counts['unconverged']}; stability_map.nc: `decided`, "
                "`converged`; docs/stability.md)",
                markup=False,
                highlight=False,
                soft_wrap=True,
            )
    from ..study.files import resonances

    peaks = [
        f"{p['body']} ({p['node']}) {p['speed_rpm']:.0f} rpm, AF "
        + ("n/a (half-power band not in the sweep)" if p["amplification_factor"] is None
           else f"{p['amplification_factor']:.3g}")
        for p in resonances(result)
    ]  # fmt: skip
    if peaks:
        console.print(
            "resonances (half-power amplification factor, API 684): " + "; ".join(peaks),
            markup=False,
            highlight=False,
            soft_wrap=True,
        )
    from .peaks import coarse_note

    coarse = coarse_note([p for p in resonances(result) if not p["resolved"]])
    if coarse:
        err.print(f"warning: {coarse}", markup=False, highlight=False, soft_wrap=True)
    for w in result.warnings:
        err.print(f"warning: {w}", markup=False, highlight=False, soft_wrap=True)
    if result.written:
        console.print("wrote " + ", ".join(str(p) for p in result.written), highlight=False)


def register(app: typer.Typer) -> None:
    """Add ``sweep`` to the ``rheolin`` application."""
    app.command("sweep")(sweep)


def _one_unit(text: str) -> str:
    """``"900 rpm, 1200 rpm"`` -> ``"900, 1200 rpm"`` when no parameter values intervene."""
    parts = text.split(", ")
    if all(p.endswith(" rpm") for p in parts) and len(parts) > 1:
        return ", ".join(p[: -len(" rpm")] for p in parts[:-1]) + ", " + parts[-1]
    return text
