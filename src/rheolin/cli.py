"""Command line ``rheolin``: the terminal belongs to this module only.

Exit codes: 0 success; 1 the computation did not succeed (not converged or unstable);
2 invalid input (model file or options).
"""

from __future__ import annotations

import time

import typer
from rich.console import Console
from rich.table import Table

from . import __version__
from .examples import chain_with_mesh
from .floquet import floquet
from .harmonics import HarmonicSet
from .solvers import METHODS, solve
from .solvers.solve import stability_harmonics

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="rheolin: periodic steady state and stability of rotating transmissions.",
)
console = Console()


@app.callback()
def _root() -> None:
    """rheolin: periodic steady state and stability of rotating transmissions."""


@app.command()
def version() -> None:
    """Print the version."""
    console.print(__version__)


@app.command()
def demo(
    dofs: int = typer.Option(600, help="Size of the demo chain (DOF)."),
    harmonics: int = typer.Option(2, help="Closure order of the harmonic set."),
) -> None:
    """Solve a small geared chain with an asymmetric rotating body by every method."""
    system = chain_with_mesh(dofs)
    hset = HarmonicSet.closure(system, order=harmonics)
    positive = [k for k in system.coefficient_harmonics if k > 0]
    console.print(
        f"[bold]Demo system[/bold]: {system.n} DOF, base frequency {system.omega:.2f} rad/s, "
        f"coefficient harmonics ±{positive}, {len(hset)} harmonics in the closure set"
    )
    table = Table(title="Periodic steady state by method")
    for col in ("method", "success", "iterations", "residual", "seconds", "max |q| [m]"):
        table.add_column(col, justify="left" if col == "method" else "right")
    reference = None
    notes: list[str] = []
    for method in ("gmres", "perturbation", "direct"):
        if method not in METHODS:
            continue
        t0 = time.perf_counter()
        sol = solve(system, hset, method=method, stability=False)
        dt = time.perf_counter() - t0
        if reference is None and sol.success:
            reference = sol
        amp = float(abs(sol.q).max())
        table.add_row(
            method,
            "yes" if sol.success else "[red]no[/red]",
            str(sol.iterations),
            f"{sol.residual:.2e}",
            f"{dt:.3f}",
            f"{amp:.3e}",
        )
        notes.append(f"{method}: {sol.message}")
    console.print(table)
    for note in notes:
        console.print(f"  {note}")
    small = chain_with_mesh(12, teeth=5, mesh_harmonics=2)
    stab = floquet(small, stability_harmonics(small))
    console.print(
        f"Floquet (Hill) check on a 12-DOF variant with 5 teeth: largest real part "
        f"{stab.max_real:.3g} 1/s -> {'stable' if stab.stable else '[red]unstable[/red]'}"
    )
    if reference is None:
        raise typer.Exit(1)


def main() -> None:
    """Entry point of the ``rheolin`` script."""
    app()


if __name__ == "__main__":
    main()
