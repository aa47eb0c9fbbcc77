"""What every ``rheolin`` command shares: the console, the options several commands take, and
the checks before any computation (options, output directory, memory budget).

>>> [stability_flag(s) for s in ("auto", "on", "OFF")]
[None, True, False]
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np
import typer
from rich.console import Console

from ..harmonics.sets import TruncationWarning
from .errors import UserError, err
from .report import print_operating_point

__all__ = [
    "HARMONICS",
    "MAX_ORDER",
    "METHOD",
    "MODEL",
    "OUT",
    "RTOL",
    "STABILITY",
    "Notes",
    "console",
    "fail",
    "load",
    "output_dir",
    "preflight",
    "show_operating_point",
    "solve_options",
    "stability_fits",
    "stability_flag",
]

#: The terminal for results (messages go to :data:`rheolin.cli.errors.err`).
console = Console(emoji=False, highlight=False)

MODEL = typer.Argument(..., help="Model file (TOML, see docs/model-format.md).")
OUT = typer.Option(None, "--out", "-o", help="Output directory (created).")
METHOD = typer.Option("auto", help="Solver: auto or any registered method (see --help of run).")
HARMONICS = typer.Option(
    None, "--harmonics", help="Closure order of the harmonic set (default: the file's, else 2)."
)
MAX_ORDER = typer.Option(
    None,
    "--max-order",
    help="Frequency cut-off in orders of the input speed (default: the file's, else none).",
)
STABILITY = typer.Option(
    "auto",
    help="Floquet check: auto (when it fits the memory budget), on, off.",
    case_sensitive=False,
)
RTOL = typer.Option(
    1e-10,
    "--rtol",
    help="Convergence criterion: backward error ||f - A q|| / (||A|| ||q|| + ||f||) "
    "(docs/solvers.md), in (0, 0.1).",
)
FLOQUET_RTOL = typer.Option(
    None,
    "--floquet-rtol",
    help="Relative accuracy of the largest Floquet real part (default: 1e-4 for run, not "
    "refined beyond the verdict's own for sweep and campbell; docs/stability.md).",
)


def floquet_rtol(value: float | None) -> float | None:
    """``--floquet-rtol`` checked: a number > 0 (None: the default)."""
    if value is not None and not (np.isfinite(value) and value > 0):
        raise fail(f"--floquet-rtol: must be a number > 0, got {value}")
    return value


def fail(message: str) -> UserError:
    """An invalid option: raised, the contract prints it plainly and exits 2."""
    return UserError(message)


class Notes:
    """Collect the warnings rheolin raises about a run (e.g. a truncated harmonic set), once
    each, for the console and the JSON summary."""

    def __init__(self) -> None:
        self.messages: list[str] = []
        self._catch = warnings.catch_warnings(record=True)

    def __enter__(self) -> Notes:
        self._caught = self._catch.__enter__()
        warnings.simplefilter("always", TruncationWarning)
        return self

    def __exit__(self, *exc: Any) -> None:
        self._catch.__exit__(*exc)
        for w in self._caught:
            if issubclass(w.category, TruncationWarning):
                if str(w.message) not in self.messages:
                    self.messages.append(str(w.message))
            else:
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)

    def show(self) -> None:
        """Print the collected warnings to stderr, one line each."""
        for m in self.messages:
            err.print(f"warning: {m}", markup=False, highlight=False, soft_wrap=True)


def load(path: Path) -> Any:
    """The :class:`~rheolin.io.LoadedModel` of a model file (a user error when invalid)."""
    from ..io import read_model

    return read_model(path)


def solve_options(
    lm: Any,
    method: str,
    harmonics: int | None,
    max_order: float | None,
    stability: str,
    rtol: float = 1e-10,
) -> dict[str, Any]:
    """The solver options of ``run`` and ``sweep``, checked; the file's ``[harmonics]`` where
    the command line gives none."""
    from ..solvers import METHODS

    allowed = ["auto", *sorted(METHODS)]
    if method not in allowed:
        raise fail(f"--method: must be one of {allowed}, got {method!r}")
    if harmonics is not None and harmonics < 0:
        raise fail(f"--harmonics: must be >= 0, got {harmonics}")
    if max_order is not None and not (np.isfinite(max_order) and max_order > 0):
        raise fail(f"--max-order: must be a finite number > 0, got {max_order}")
    if not (np.isfinite(rtol) and 0.0 < rtol < 0.1):
        raise fail(f"--rtol: must be a number in (0, 0.1), got {rtol}")
    h = lm.spec.harmonics
    return dict(
        method=method,
        order=h.order if harmonics is None else harmonics,
        max_order=h.max_order if max_order is None else max_order,
        stability=stability_flag(stability),
        rtol=float(rtol),
    )


def stability_flag(stability: str) -> bool | None:
    """``--stability`` auto/on/off as None/True/False."""
    flags = {"auto": None, "on": True, "off": False}
    if stability.lower() not in flags:
        raise fail(f"--stability: must be auto, on or off, got {stability!r}")
    return flags[stability.lower()]


def output_dir(out: Path | None, default: str) -> Path:
    """The output directory, refused before any computation when it cannot be written."""
    from ..io.outdir import check_output_dir

    return check_output_dir(Path(out) if out is not None else Path(default), "--out")


def preflight(
    lm: Any,
    speeds: Any,
    order: int | None,
    max_order: float | None,
    needs_load: bool = True,
    stability: bool | None = None,
) -> Any:
    """Physical admissibility and sizes against the memory budget, before any work; with
    ``stability=True`` (``--stability on``) the Floquet check's estimate too."""
    from ..io.preflight import preflight as check

    info = check(lm, speeds, order=order, max_order=max_order, needs_load=needs_load)
    if stability:
        stability_fits(lm, speeds)
    return info


def stability_fits(lm: Any, speeds: Any) -> None:
    """Refuse (exit 2) a Floquet check that cannot fit the memory budget, with its estimate
    and what to change; nothing large is built (the model is assembled at one speed)."""
    from ..budget import format_bytes, memory_budget
    from ..floquet import floquet_memory

    listed = [float(x) for x in np.atleast_1d(speeds if speeds is not None else [])]
    speed = max(listed) if listed else 100.0
    system = lm.model.assemble(speed).system
    kind, estimate = floquet_memory(system)
    limit = memory_budget()
    if estimate > limit:
        raise fail(
            f"--stability on: the {kind} Floquet check of {system.n} DOF needs an estimated "
            f"{format_bytes(estimate)}, more than the memory budget of {format_bytes(limit)}; "
            "condense bodies (rheolin condense), mesh the shafts more coarsely, use "
            "--stability auto (it reports the check as not done), or raise the budget "
            "(RHEOLIN_MEMORY_BUDGET)"
        )


def show_operating_point(model: Any, speed: float, where: str) -> None:
    """Print the preloaded operating point (static equilibrium) a preloaded model is solved
    about: every speed of a sweep or Campbell diagram is linearized there."""
    if not model.preloaded:
        return
    console.print(f"[dim]operating point at {speed * 30 / np.pi:.1f} rpm ({where}):[/dim]")
    print_operating_point(console, model.operating_point(speed).to_dict())
