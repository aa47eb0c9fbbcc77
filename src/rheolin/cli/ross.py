"""``rheolin import-ross``: a rotor saved by ROSS -> a rheolin model file (on stdout or -o)."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console
from rich.markup import escape

from ..errors import ModelError

__all__ = ["import_ross", "register"]


ROTOR = typer.Argument(..., help="Rotor file saved by ROSS (Rotor.save, .toml/.json).")
OUT = typer.Option(
    None, "--out", "-o", help="Write the model file here (atomically) instead of stdout."
)


def import_ross(rotor: Path = ROTOR, out: Path | None = OUT) -> None:
    """Convert a ROSS rotor file to a rheolin model file (ROSS itself is not needed)."""
    from ..io.ross import model_from_ross

    try:
        text = model_from_ross(rotor).to_toml(out)
    except ModelError as exc:
        Console(stderr=True).print(
            f"[red]error:[/red] {escape(str(exc))}", highlight=False, soft_wrap=True
        )
        raise typer.Exit(2) from None
    if out is None:
        typer.echo(text, nl=False)


def register(app: typer.Typer) -> None:
    """Add ``import-ross`` to the ``rheolin`` application."""
    app.command("import-ross")(import_ross)
