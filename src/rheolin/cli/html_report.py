"""``rheolin report DIR``: one self-contained HTML report of a result directory (and the
``--report`` of ``run``, ``sweep`` and ``campbell``)."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.markup import escape

from .common import console, fail
from .errors import EXIT_FAILED, err
from .progress import working

__all__ = ["parse_operating", "register", "report", "write_report_for"]

DIRECTORY = typer.Argument(..., help="Result directory of run, sweep, campbell, modes or frf.")
MODEL_FILE = typer.Option(
    None, "--model", help="The model file (default: the one the results record, if found)."
)
OPERATING = typer.Option(
    None,
    "--operating",
    help="Operating speed range for the API 617 separation margins, e.g. 2800:3200rpm "
    "(default: the model file's speed).",
)
REPORT_OUT = typer.Option(None, "--out", "-o", help="HTML file (default: DIR/report.html).")
NODES = typer.Option(False, "--nodes", help="Node numbers in the model drawing.")


def parse_operating(text: str | None) -> tuple[float, float] | None:
    """``"2800:3200rpm"`` (or one speed) -> ``(2800.0, 3200.0)`` [rpm].

    >>> parse_operating("2800:3200rpm"), parse_operating("50 Hz")
    ((2800.0, 3200.0), (3000.0, 3000.0))
    """
    import math

    from .parse import parse_speed

    if text is None:
        return None
    parts = text.split(":")
    if len(parts) > 2 or not all(p.strip() for p in parts):
        raise fail(f"--operating: write MIN:MAX with a unit, e.g. 2800:3200rpm; got {text!r}")
    unit = "".join(c for c in parts[-1] if c.isalpha() or c == "/").strip()
    values = [
        parse_speed(p if any(c.isalpha() for c in p) else f"{p}{unit}", "--operating")
        for p in parts
    ]
    rpm = [round(v * 30 / math.pi, 9) for v in values]
    lo, hi = rpm[0], rpm[-1]
    if hi < lo:
        raise fail(f"--operating: MIN must not exceed MAX, got {text!r}")
    return lo, hi


def write_report_for(
    directory: Path,
    model: Path | None = None,
    operating: tuple[float, float] | None = None,
    nodes: bool = False,
    path: Path | None = None,
) -> tuple[Path, list[str]]:
    """Write the report of ``directory`` and say where (``--report`` and ``rheolin report``);
    each part left out is warned of on stderr, naming the file and why. Returns the report's
    path and those lines."""
    from ..io.outdir import check_output_dir
    from ..report import write_report

    target = Path(path) if path is not None else Path(directory) / "report.html"
    check_output_dir(target.parent, "--out")
    left_out: list[str] = []
    with working(f"report of {directory}"):
        out = write_report(
            directory,
            model=model,
            operating_rpm=operating,
            nodes=nodes,
            path=target,
            left_out=left_out,
        )
    console.print(f"wrote {escape(str(out))}", highlight=False)
    for note in left_out:  # one line each (a reader's message may go on with links)
        line = note.splitlines()[0] if note.strip() else note
        err.print(f"warning: report: {line}", markup=False, highlight=False, soft_wrap=True)
    return out, left_out


def report(
    directory: Path = DIRECTORY,
    model: Path | None = MODEL_FILE,
    operating: str | None = OPERATING,
    out: Path | None = REPORT_OUT,
    nodes: bool = NODES,
) -> None:
    """Write one self-contained HTML report of a result directory (opens offline): verdicts,
    the model drawing, interactive figures, critical speeds, resonances with amplification
    factors and separation margins, unstable ranges, the inputs for traceability."""
    from ..report.collect import FILES

    if not directory.is_dir():
        raise fail(f"DIRECTORY: {str(directory)!r} is not a directory")
    if not any((directory / name).is_file() for name in FILES):
        raise fail(f"DIRECTORY: {str(directory)!r} holds no result file ({', '.join(FILES)})")
    if model is not None and not model.is_file():
        raise fail(f"--model: {str(model)!r} is not a file")
    if out is not None and out.is_dir():
        raise fail(f"--out: {str(out)!r} is a directory; give an HTML file name")
    _, left_out = write_report_for(directory, model, parse_operating(operating), nodes, out)
    if left_out:  # the report is written but incomplete: docs/cli.md, exit codes
        raise typer.Exit(EXIT_FAILED)


def register(app: typer.Typer) -> None:
    """Add ``report`` to the ``rheolin`` application."""
    app.command("report")(report)
