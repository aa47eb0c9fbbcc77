"""``rheolin draw``: the drawing of a model file (shafts, disks, gears, bearings, meshes)."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.markup import escape

from .common import MODEL, console, fail, load
from .progress import working

__all__ = ["draw", "register"]

DRAW_OUT = typer.Option(
    None, "--out", "-o", help="Image file: .png (default), .svg or .pdf; default MODEL_drawing.png."
)
NODES = typer.Option(False, "--nodes", help="Write every node's index under it.")


def draw(model: Path = MODEL, out: Path | None = DRAW_OUT, nodes: bool = NODES) -> None:
    """Draw a model: a side view of every shaft line and the gear train seen along the axis;
    written to --out (PNG, SVG or PDF by the suffix)."""
    from ..io.outdir import check_output_dir
    from ..plots._common import FORMATS
    from ..plots.drawing import draw_model

    lm = load(model)
    path = Path(out) if out is not None else model.with_name(f"{model.stem}_drawing.png")
    suffix = path.suffix.lower().lstrip(".")
    if suffix not in FORMATS:
        raise fail(f"--out: {str(path)!r}: the suffix must be one of .png, .svg, .pdf")
    if path.is_dir():
        raise fail(f"--out: {str(path)!r} is a directory; give an image file name")
    check_output_dir(path.parent if str(path.parent) else Path("."), "--out")
    name = lm.spec.model.name or model.stem
    with working(f"drawing {model.name}"):
        draw_model(lm.model, path, nodes=nodes, title=f"{name} ({model.name})")
    console.print(f"wrote {escape(str(path))}", highlight=False)


def register(app: typer.Typer) -> None:
    """Add ``draw`` to the ``rheolin`` application."""
    app.command("draw")(draw)
