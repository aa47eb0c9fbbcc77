"""``rheolin modes``: the modes at one speed, labelled, with their shapes plotted."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer
from rich.markup import escape
from rich.table import Table

from .common import MODEL, OUT, console, fail, load, output_dir
from .errors import set_kept, sigterm_as_interrupt
from .parse import parse_speeds
from .progress import working

__all__ = ["modes", "register"]

MODES_FILES = {"modes.nc", "modes.png"}

SPEED = typer.Option(..., help="Input speed, e.g. 3000rpm (0: standstill).")
COUNT = typer.Option(12, help="How many of the lowest modes to list and draw (at most 16 drawn).")


def modes(
    model: Path = MODEL, speed: str = SPEED, count: int = COUNT, out: Path | None = OUT
) -> None:
    """Modes of the time-averaged system at one speed: frequency, damping, kind (lateral
    forward/backward, torsional, axial, coupled); DIR/modes.nc (with the shapes) and
    DIR/modes.png (deflected lines and whirl orbits)."""
    import xarray as xr

    from ..io.outdir import staged_output
    from ..plots.modes import plot_mode_shapes
    from ..results.dataset import write_dataset
    from ..results.units import speed_attrs
    from ..stability.campbell import STANDSTILL
    from ..stability.modes import averaged_modes, mode_energy, mode_kind, whirl_ratio

    lm = load(model)
    (w,) = parse_speeds(speed, "--speed", allow_zero=True)[:1]
    if count < 1:
        raise fail(f"--count: must be >= 1, got {count}")
    W = float(w) if w > 0 else STANDSTILL
    out_dir = output_dir(out, f"{model.stem}_modes")
    set_kept(f"nothing written; {out_dir} is unchanged")
    m = lm.model
    with sigterm_as_interrupt(), working(f"modes at {float(w) * 30 / np.pi:.6g} rpm"):
        a = m.assemble(W)
        am = averaged_modes(a.system, count)
        axes = {b: m.bodies[b].axis for b in m.bodies}
        ratio = whirl_ratio(am.shapes, a.dof_labels, axes, a.plan.spin)
        energy = mode_energy(am.shapes, a.dof_labels, axes, a.system.M[0])
        kinds = mode_kind(energy, ratio)
    labels = [f"{b}:{n}:{c}" for b, n, c in a.dof_labels]
    ds = xr.Dataset(
        {
            "frequency": (
                "mode",
                am.frequency / (2 * np.pi),
                {"units": "Hz", "long_name": "damped natural frequency"},
            ),
            "damping_ratio": ("mode", am.damping_ratio, {"units": "1"}),
            "log_decrement": ("mode", am.log_decrement, {"units": "1"}),
            "whirl_ratio": ("mode", ratio, {"units": "1"}),
            "kind": ("mode", np.asarray(kinds, dtype=str)),
            "energy_share": (("mode", "motion"), energy, {"units": "1"}),
            "shape": (
                ("mode", "dof", "part"),
                np.stack([am.shapes.T.real, am.shapes.T.imag], -1),
                {"units": "1", "long_name": "mode shape, unit 2-norm (m and rad per DOF)"},
            ),
        },
        coords={
            "mode": ("mode", np.arange(am.frequency.size), {"units": "1"}),
            "dof": labels,
            "motion": ["lateral", "torsional", "axial", "other"],
            "part": ["real", "imag"],
        },
        attrs={
            **speed_attrs(float(w)),
            "rigid_body_modes": int(am.rigid_eigenvalues),
            "model_file": str(model),
            "model_sha256": lm.sha256,
        },
    )
    with sigterm_as_interrupt(), staged_output(out_dir, MODES_FILES) as stage:
        write_dataset(ds, stage / "modes.nc")
        plot_mode_shapes(m, W, stage / "modes.png", n_modes=count)
    set_kept(None)
    table = Table(title=f"modes of {escape(model.name)} at {float(w) * 30 / np.pi:.0f} rpm")
    for col in ("mode", "frequency (Hz)", "damping ratio", "kind"):
        table.add_column(col, justify="left" if col == "kind" else "right")
    for i in range(am.frequency.size):
        zeta = float(am.damping_ratio[i])
        table.add_row(
            str(i),
            f"{am.frequency[i] / (2 * np.pi):.3f}",
            f"{0.0 if abs(zeta) < 1e-12 else zeta:.4g}",
            str(kinds[i]),
        )
    console.print(table)
    if am.rigid_eigenvalues:
        console.print(
            f"{am.rigid_eigenvalues} rigid-body eigenvalues (a free axial or torsional "
            "motion) left out"
        )
    console.print(
        f"wrote {out_dir / 'modes.nc'}, {out_dir / 'modes.png'}", markup=False, highlight=False
    )


def register(app: typer.Typer) -> None:
    """Add ``modes`` to the ``rheolin`` application."""
    app.command("modes")(modes)
