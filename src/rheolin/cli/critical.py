"""``rheolin critical-map``: undamped critical speeds against bearing stiffness."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import typer
from rich.markup import escape
from rich.table import Table

from .common import MODEL, OUT, console, fail, load, output_dir
from .errors import set_kept, sigterm_as_interrupt
from .progress import working

__all__ = ["critical_map", "register"]

MAP_FILES = {"critical_map.nc", "critical_map.png"}

STIFFNESS = typer.Option(
    "1e5:1e10:26", help="start:stop:count, log-spaced, e.g. '1e5:1e10:26 N/m'."
)
BEARING = typer.Option(
    None, "--bearing", help="A bearing to vary (repeatable; default: every bearing to ground)."
)
COUNT = typer.Option(4, help="How many critical speeds per stiffness.")

_RANGE = re.compile(r"^\s*([-+0-9.eE]+)\s*:\s*([-+0-9.eE]+)\s*:\s*([0-9]+)\s*(.*)$")


def _stiffness(text: str) -> np.ndarray:
    from ..io.units import UnitError, to_si

    m = _RANGE.match(text)
    if not m:
        raise fail(f"--stiffness: write start:stop:count, e.g. '1e5:1e10:26 N/m', got {text!r}")
    unit = m.group(4).strip() or "N/m"
    try:
        lo, hi = (to_si(f"{m.group(i)} {unit}", "stiffness") for i in (1, 2))
    except (UnitError, ValueError) as exc:
        raise fail(f"--stiffness: {exc}") from None
    count = int(m.group(3))
    if not (0 < lo < hi and 2 <= count <= 1000):
        raise fail(f"--stiffness: need 0 < start < stop and 2 <= count <= 1000, got {text!r}")
    return np.logspace(np.log10(lo), np.log10(hi), count)


def critical_map(
    model: Path = MODEL,
    stiffness: str = STIFFNESS,
    bearings: list[str] | None = BEARING,
    count: int = COUNT,
    out: Path | None = OUT,
) -> None:
    """Undamped critical-speed map: the forward synchronous critical speeds with every
    bearing's transverse stiffness set to each value (isotropic, undamped); DIR/critical_map.nc
    and DIR/critical_map.png, and the critical speeds at the model's own stiffness printed."""
    from ..errors import ModelError
    from ..io.outdir import staged_output
    from ..plots.campbell import plot_critical_map
    from ..results.dataset import write_dataset
    from ..stability.critical_map import critical_speed_map, synchronous_critical_speeds

    lm = load(model)
    k = _stiffness(stiffness)
    if count < 1:
        raise fail(f"--count: must be >= 1, got {count}")
    out_dir = output_dir(out, f"{model.stem}_critical_map")
    set_kept(f"nothing written; {out_dir} is unchanged")
    with sigterm_as_interrupt(), working(f"critical speeds at {k.size} stiffness values"):
        try:
            result = critical_speed_map(lm.model, k, bearings=bearings or None, n_modes=count)
        except ModelError as exc:
            raise fail(f"--bearing: {exc}" if "bearing" in str(exc) else str(exc)) from None
        own = synchronous_critical_speeds(lm.model, count)
    with sigterm_as_interrupt(), staged_output(out_dir, MAP_FILES) as stage:
        write_dataset(result.to_dataset(), stage / "critical_map.nc")
        plot_critical_map(result, stage / "critical_map.png")
    set_kept(None)
    table = Table(title=f"undamped critical speeds of {escape(model.name)} (its own bearings)")
    table.add_column("critical speed", justify="right")
    table.add_column("rpm", justify="right")
    for i, w in enumerate(own):
        table.add_row(str(i + 1), f"{w * 30 / np.pi:.1f}")
    console.print(table)
    console.print(
        f"varied: {', '.join(result.bearings)}; wrote {out_dir / 'critical_map.nc'}, "
        f"{out_dir / 'critical_map.png'}",
        markup=False,
        highlight=False,
    )


def register(app: typer.Typer) -> None:
    """Add ``critical-map`` to the ``rheolin`` application."""
    app.command("critical-map")(critical_map)
