"""``rheolin import-ross``: a rotor saved by ROSS -> a rheolin model file (on stdout or -o)."""

from __future__ import annotations

from pathlib import Path

import typer

from .common import fail

__all__ = ["import_ross", "register"]


ROTOR = typer.Argument(..., help="Rotor file saved by ROSS (Rotor.save, .toml/.json).")
OUT = typer.Option(
    None, "--out", "-o", help="Write the model file here (atomically) instead of stdout."
)


def import_ross(rotor: Path = ROTOR, out: Path | None = OUT) -> None:
    """Convert a ROSS rotor file to a rheolin model file (ROSS itself is not needed)."""
    from ..io.ross import model_from_ross

    if out is not None and (out.is_dir() or not out.parent.is_dir()):
        what = "is a directory" if out.is_dir() else f"has no directory {str(out.parent)!r}"
        raise fail(f"--out: {str(out)!r} {what}; give a file path for the model file")
    text = model_from_ross(rotor).to_toml(out)  # a ModelError names the element and field
    if out is None:
        typer.echo(text, nl=False)


def register(app: typer.Typer) -> None:
    """Add ``import-ross`` to the ``rheolin`` application."""
    app.command("import-ross")(import_ross)
