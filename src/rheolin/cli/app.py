"""Command line ``rheolin``: the Typer application, which registers every command module.

Exit codes (every command; :mod:`rheolin.cli.errors` holds the contract):

* 0 -- success;
* 1 -- the computation ran but did not succeed (not converged, or the operating point is
  unstable); results are still written and say so;
* 2 -- invalid input: model file, options, output path, a problem too large for the memory
  budget, or a command whose optional part is missing; one plain line per problem naming the
  field, what was given and what is allowed; checked before any computation;
* 3 -- internal error (a bug): one short line; ``rheolin --debug ...`` shows the traceback;
* 130 -- interrupted (Ctrl-C, SIGTERM): says what was kept.

Each command lives in its own module with a ``register(app)`` function; this module, at the
top of the package, is the only one that imports them, so no command imports the application.
"""

from __future__ import annotations

from pathlib import Path

import typer

from .. import __version__
from . import (
    campbell,
    condense,
    critical,
    draw,
    files,
    frf,
    html_report,
    modes,
    point,
    ross,
    sweep,
)
from .common import console
from .errors import ContractGroup, set_debug

__all__ = ["app", "main"]

app = typer.Typer(
    cls=ContractGroup,
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="rheolin: periodic steady state and stability of rotating transmissions. "
    "Exit codes: 0 success, 1 not converged or unstable, 2 invalid input, "
    "3 internal error, 130 interrupted.",
)

DEMO_OUT = typer.Option(Path("demo_results"), help="Output directory.")


def _print_version(value: bool) -> None:
    """``rheolin --version``: print the program name and version, then exit 0."""
    if value:
        console.print(f"rheolin {__version__}", markup=False)
        raise typer.Exit()


@app.callback()
def _root(
    debug: bool = typer.Option(
        False, "--debug", help="Show the traceback of an internal error (exit code 3)."
    ),
    version: bool = typer.Option(
        False,
        "--version",
        help="Print the version and exit.",
        is_eager=True,
        callback=_print_version,
    ),
) -> None:
    """rheolin: periodic steady state and stability of rotating transmissions."""
    set_debug(debug)


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


def _invoke(args: list[str]) -> int:
    code = app(args, standalone_mode=False)
    return int(code) if isinstance(code, int) else 0


# the order of `rheolin --help`
files.register(app)
point.register(app)
sweep.register(app)
campbell.register(app)
app.command("demo")(demo)
ross.register(app)
condense.register(app)
frf.register(app)
critical.register(app)
modes.register(app)
draw.register(app)
html_report.register(app)


def main() -> None:
    """Entry point of the ``rheolin`` script."""
    app()


if __name__ == "__main__":
    main()
