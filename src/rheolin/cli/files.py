"""``rheolin version``, ``rheolin validate`` and ``rheolin example``: the commands about files
and the program rather than a computation."""

from __future__ import annotations

import sys
from pathlib import Path

import typer
from rich.markup import escape

from .. import __version__
from ..errors import ModelError
from .common import MODEL, console, fail, load, output_dir, preflight
from .progress import working

__all__ = ["example", "register", "validate", "version"]

EXAMPLE_OUT = typer.Option(
    None, "--out", "-o", help="Write the example's files into this directory."
)


def version() -> None:
    """Print the version."""
    console.print(__version__)


def validate(model: Path = MODEL) -> None:
    """Check a model file; exit 0 if valid, 2 with the field paths of every problem if not."""
    lm = load(model)
    m = lm.model
    info = preflight(lm, None, None, None, needs_load=False)
    console.print(
        f"{model}: valid: {len(m.bodies)} bodies, {len(m.joints)} bearings/couplings, "
        f"{len(m.meshes)} gear meshes, {len(m.forces)} forces; w1 = "
        f"{m.speed_plan().base} x input speed; {info.describe()}",
        markup=False,
    )
    if m.preloaded:  # the static equilibrium must exist (at the file's speed, if it has one)
        speed = lm.spec.model.speed or 1.0
        try:
            op = m.operating_point(speed)
        except ModelError as exc:
            raise fail(f"{model}: {exc}") from None
        peak, (body, node) = op.max_displacement()
        console.print(
            f"preloaded: {len(m.rolling)} rolling bearings, {len(m.torques)} torques, "
            f"{sum(g.get('load_law') is not None for g in m.meshes.values())} load-dependent "
            f"meshes; static equilibrium found ({op.iterations} Newton iterations; largest "
            f"deflection {peak * 1e6:.3g} um at {body} node {node})",
            markup=False,
        )


def example(
    name: str = typer.Argument("gearbox", help="Example name."),
    out: Path | None = EXAMPLE_OUT,
) -> None:
    """Write a built-in example model file to stdout (rheolin example gearbox > model.toml), or
    its files into --out; gearbox-housing builds its FE housing (scikit-fem) into --out."""
    from ..data import EXAMPLES, example_text

    built = {"gearbox-housing": "the gearbox in a flexible FE housing (needs --out, scikit-fem)"}
    if name not in EXAMPLES and name not in built:
        listing = ", ".join(f"{k} ({v})" for k, v in {**EXAMPLES, **built}.items())
        raise fail(f"no example named {name!r}; examples: {listing}")
    if name in built:
        if out is None:
            raise fail(f"--out: the {name} example writes two files; give a directory")
        from ..fe.gearbox_housing import build

        directory = output_dir(out, str(out))
        with working("gearbox-housing: meshing the housing, its FE matrices, condensing them"):
            path = build(directory)
        console.print(
            f"wrote {escape(str(path))} and {escape(str(directory / 'housing.npz'))}; "
            f"run: rheolin run {escape(str(path))}",
            highlight=False,
        )
        return
    if out is None:
        sys.stdout.write(example_text(name))
        return
    directory = output_dir(out, str(out))
    from ..io.atomic import atomic_write

    with atomic_write(directory / f"{name}.toml") as tmp:
        tmp.write_text(example_text(name))
    console.print(f"wrote {escape(str(directory / f'{name}.toml'))}", highlight=False)


def register(app: typer.Typer) -> None:
    """Add ``version``, ``validate`` and ``example`` to the ``rheolin`` application."""
    app.command("version")(version)
    app.command("validate")(validate)
    app.command("example")(example)
