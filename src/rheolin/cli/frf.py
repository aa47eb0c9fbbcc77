"""``rheolin frf``: frequency response functions at a fixed speed, with a Bode plot."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer
from rich.markup import escape
from rich.table import Table

from .common import MODEL, OUT, console, fail, load, output_dir, stability_flag
from .errors import EXIT_FAILED, set_kept, sigterm_as_interrupt
from .parse import parse_speed, parse_speeds
from .progress import counted, working

__all__ = ["frf", "register"]

FRF_FILES = {"frf.nc", "bode.png"}

#: Peaks below this share of a pair's largest magnitude are not listed.
PEAK_SHARE = 0.01

SPEED = typer.Option(..., help="Input speed, e.g. 3000rpm.")
FREQUENCIES = typer.Option(
    ..., help="Excitation frequencies start:stop:step with unit, e.g. 1:500:0.5Hz."
)
INPUT = typer.Option(
    ..., "--input", help="Excited DOF body:node:component (ux uy uz phix phiy phiz); repeatable."
)
OUTPUT = typer.Option(
    None, "--output", help="Response DOF body:node:component; repeatable (default: the inputs)."
)
ORDER = typer.Option(
    None, help="Lattice order of the sidebands of a time-periodic model (default 2)."
)
UNBALANCE = typer.Option(
    False, "--unbalance", help="Scale each input by w^2: the response per kg m of unbalance."
)
STABILITY = typer.Option(
    "auto", help="Floquet check at the speed: auto (when it fits), on, off.", case_sensitive=False
)


def frf(
    model: Path = MODEL,
    speed: str = SPEED,
    frequencies: str = FREQUENCIES,
    inputs: list[str] = INPUT,
    outputs: list[str] | None = OUTPUT,
    order: int | None = ORDER,
    unbalance: bool = UNBALANCE,
    stability: str = STABILITY,
    out: Path | None = OUT,
) -> None:
    """Frequency response at a fixed speed (non-synchronous excitation): DIR/frf.nc and
    DIR/bode.png; the resonance peaks printed with their half-power amplification factors."""
    from ..budget import format_bytes, memory_budget
    from ..floquet import floquet, floquet_memory
    from ..io.outdir import staged_output
    from ..plots.frf import plot_bode
    from ..results.api684 import amplification_factors
    from ..results.dataset import write_dataset
    from ..results.frf import frequency_response, parse_dof

    lm = load(model)
    w_speed = parse_speed(speed)
    w = parse_speeds(frequencies, "--frequencies", allow_zero=True)
    flag = stability_flag(stability)
    if order is not None and order < 0:
        raise fail(f"--order: must be >= 0, got {order}")
    assembled = lm.model.assemble(w_speed)
    for option, dofs in (("--input", inputs), ("--output", outputs or [])):
        for d in dofs:
            try:
                parse_dof(d, assembled.dof_labels)
            except Exception as exc:
                raise fail(f"{option}: {exc}") from None
    out_dir = output_dir(out, f"{model.stem}_frf")
    set_kept(f"nothing written; {out_dir} is unchanged")
    with sigterm_as_interrupt():
        with counted("frequency response", w.size, "frequencies") as step:
            res = frequency_response(
                lm.model,
                w_speed,
                w,
                inputs,
                outputs or None,
                order=order,
                unbalance=unbalance,
                progress=step,
            )
        verdict, why = None, ""
        if flag is not False:
            kind, estimate = floquet_memory(assembled.system)
            if flag is None and estimate > memory_budget():
                why = (
                    f"the {kind} Hill problem needs an estimated {format_bytes(estimate)}, more "
                    f"than the memory budget of {format_bytes(memory_budget())}"
                )
            else:
                with working("Floquet stability"):
                    verdict = floquet(assembled.system)
        else:
            why = "--stability off"
    with sigterm_as_interrupt(), staged_output(out_dir, FRF_FILES) as stage:
        ds = res.to_dataset()
        ds.attrs.update(model_file=str(model), model_sha256=lm.sha256)
        if verdict is not None:
            ds.attrs["stable"] = int(verdict.stable)
            ds.attrs["max_floquet_real"] = float(verdict.max_real)
        write_dataset(ds, stage / "frf.nc")
        plot_bode(res, stage / "bode.png")
    set_kept(None)
    unit = "m/(kg m)" if unbalance else "m/N"
    rpm = w_speed * 30 / np.pi
    table = Table(title=f"resonance peaks of {escape(model.name)} at {rpm:.0f} rpm")
    for col in ("output", "input", "frequency (Hz)", f"|H| ({unit})", "phase (deg)", "AF"):
        table.add_column(col, justify="left" if col in ("output", "input") else "right")
    rows = 0
    for j, o in enumerate(res.outputs):
        for i, inp in enumerate(res.inputs):
            h = res.receptance[:, j, i]
            mag = np.abs(h)
            if not np.any(np.isfinite(mag)) or np.nanmax(mag) == 0:
                continue
            top = float(np.nanmax(mag))
            for p in amplification_factors(w, np.nan_to_num(mag)):
                if p.amplitude < PEAK_SHARE * top:
                    continue  # a ripple of the curve, not a resonance of this pair
                k = int(np.argmin(np.abs(w - p.speed)))
                af = "n/a" if p.amplification_factor is None else f"{p.amplification_factor:.1f}"
                table.add_row(
                    escape(o),
                    escape(inp),
                    f"{p.speed / (2 * np.pi):.2f}",
                    f"{p.amplitude:.3g}",
                    f"{np.degrees(np.angle(h[k])):.0f}",
                    af,
                )
                rows += 1
    console.print(table if rows else "no resonance peak inside the frequency range")
    if res.info["singular"]:
        console.print(
            f"[yellow]warning:[/yellow] the operator is singular at {len(res.info['singular'])} "
            "frequencies (an undamped resonance, or a free body at 0 Hz): NaN there"
        )
    code = 0
    if verdict is None:
        console.print(f"[yellow]stability: not checked[/yellow] ({escape(why)})")
    elif not verdict.stable:
        code = EXIT_FAILED
        console.print(
            f"[red]unstable[/red] at this speed (largest Floquet real part {verdict.max_real:.3g}"
            " 1/s): there is no steady state, and the FRF describes none"
        )
    else:
        note = "" if verdict.decided else " (undecided: the truncation could flip it)"
        console.print(f"stability (Floquet): stable{note}")
    console.print(
        f"wrote {out_dir / 'frf.nc'}, {out_dir / 'bode.png'}", markup=False, highlight=False
    )
    raise typer.Exit(code)


def register(app: typer.Typer) -> None:
    """Add ``frf`` to the ``rheolin`` application."""
    app.command("frf")(frf)
