"""Terminal rendering for the CLI (rich): the summary of one operating point and the preloaded
operating point (static equilibrium) it is solved about."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from rich.console import Console
from rich.markup import escape
from rich.table import Table

__all__ = ["print_operating_point", "print_summary"]


def _um(x: float | None) -> str:
    if x is None or not math.isfinite(x):
        return "n/a"
    return f"{x * 1e6:.3g} µm"


def _stability_detail(s: dict[str, Any]) -> str:
    """`` (lattice Hill of order 2, 35 harmonics, decided; least damped exponent ...)``."""
    if s.get("max_floquet_real") is None:
        return ""
    method = s.get("floquet_method")
    how = f"{method} Hill" if method else "Hill"
    if s.get("floquet_lattice_order") is not None:
        how += f" of order {s['floquet_lattice_order']}, {s['floquet_lattice_size']} harmonics"
    if s.get("stability_decided") is not None:
        if not s["stability_decided"]:
            how += ", UNDECIDED (truncation too coarse)"
        elif s["max_floquet_real"] > 0 and s.get("stability") != "unstable":
            how += ", marginal (an undamped motion: real part zero within its tolerance)"
        else:
            how += ", decided"
    lead = f"largest Floquet real part {s['max_floquet_real']:.4g} 1/s"
    if s.get("leading_exponent_frequency_hz") is not None:
        lead += f" at {s['leading_exponent_frequency_hz']:.5g} Hz"
    if s.get("floquet_seconds") is not None:
        how += f", {s['floquet_seconds']:.2g} s"
    mech = f"\n  mechanism: {s['stability_mechanism']}" if s.get("stability_mechanism") else ""
    return f" ({how}; {lead}){escape(mech)}"


def _num(x: Any, fmt: str, missing: str = "n/a") -> str:
    """``format(x, fmt)``, or ``missing`` for a value that was not computed (None, NaN)."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return missing
    return format(x, fmt)


def print_summary(console: Console, s: dict[str, Any], seconds: float) -> None:
    """Readable summary of one operating point (the dict of ``rheolin.results.summarize``).

    Every user-given name is escaped (a body called ``[red]`` prints as written)."""
    ok = "[green]converged[/green]" if s["success"] else "[red]NOT successful[/red]"
    console.print(
        f"[bold]Operating point[/bold] {_num(s['speed_rpm'], '.1f')} rpm "
        f"({_num(s['speed'], '.4g')} rad/s), base frequency w1 = "
        f"{_num(s['base_frequency'], '.4g')} rad/s"
    )
    res = s.get("residual")
    residual = f"backward error {_num(res, '.2e')}" if res is not None else "no residual"
    if s.get("relative_residual") is not None:
        residual += f" (||f - A q|| / ||f|| = {_num(s['relative_residual'], '.2e')})"
    console.print(
        f"method {escape(str(s['method']))} (asked: {escape(str(s['requested_method']))}), "
        f"{s['iterations']} iterations, {residual}: {ok}; {s['harmonic_count']} harmonics x "
        f"{s['n_dof']} DOF, "
        + (
            f"{seconds:.2f} s with the stability check"
            if s.get("stability") not in (None, "not checked")
            else f"solved in {seconds:.2f} s"
        )
    )
    stab = s["stability"]
    colour = {"stable": "green", "unstable": "red"}.get(stab, "yellow")
    console.print(f"stability: [{colour}]{escape(str(stab))}[/{colour}]{_stability_detail(s)}")
    console.print(f"[dim]{escape(str(s['message']))}[/dim]")
    if s.get("operating_point"):
        print_operating_point(console, s["operating_point"])
    t = Table(title="Largest responses per body (radial, single-sided amplitude)")
    for col in ("body", "node", "static", "dynamic (sum)", "largest harmonics"):
        t.add_column(col)
    for body, b in s["bodies"].items():
        tops = ", ".join(
            f"{_um(h['amplitude'])} @ {h['frequency_hz']:.1f} Hz (order {h['order']:.3g})"
            for h in b["largest_harmonics"][:2]
        )
        t.add_row(
            escape(body),
            escape(b["node"]),
            _um(b["static_radial_m"]),
            _um(b["radial_amplitude_bound_m"]),
            tops,
        )
    console.print(t)
    if s.get("bearings"):
        t = Table(title="Bearing forces (radial)")
        for col in ("bearing", "static (N)", "dynamic sum (N)", "largest harmonic"):
            t.add_column(col)
        for name, b in s["bearings"].items():
            h = b["largest_harmonics"][:1]
            top = f"{h[0]['amplitude']:.3g} N @ {h[0]['frequency_hz']:.1f} Hz" if h else "-"
            t.add_row(
                escape(name), _num(b["static_radial_N"], ".3g"),
                _num(b["dynamic_radial_sum_N"], ".3g"), top,
            )  # fmt: skip
        console.print(t)
    if s.get("meshes"):
        t = Table(title="Mesh dynamic transmission error (line of action)")
        for col in ("mesh", "mean", "largest harmonics"):
            t.add_column(col)
        for name, m in s["meshes"].items():
            tops = ", ".join(
                f"{_um(h['amplitude'])} @ {h['frequency_hz']:.1f} Hz"
                for h in m["largest_harmonics"][:2]
            )
            t.add_row(escape(name), _um(m["mean_m"]), tops)
        console.print(t)


def print_operating_point(console: Console, op: dict[str, Any]) -> None:
    """The preloaded operating point (``OperatingPoint.to_dict``): static deflection, bearing
    loads, operating stiffness of every load-dependent joint, torques."""
    where = op["max_displacement_at"]
    console.print(
        f"[bold]Static equilibrium[/bold] (preloaded operating point): largest deflection "
        f"{_um(op['max_displacement_m'])} at {escape(str(where['body']))} node {where['node']}; "
        f"{op['iterations']} Newton iterations, {op['load_steps']} load step(s), relative "
        f"residual {op['residual']:.1e}"
    )
    if op["torques_N_m"]:
        console.print(
            "torques: "
            + ", ".join(f"{escape(k)} {v:.6g} N·m" for k, v in op["torques_N_m"].items())
        )
    rows = []
    for name, b in op["bearings"].items():
        K = [[float(x) for x in row] for row in b["stiffness_N_per_m"]]
        eig = sorted(abs(float(x)) for x in _principal(K))
        contact = f"{b['in_contact']} of {b['elements']}" if b["elements"] else (
            "yes" if b["in_contact"] else "no")  # fmt: skip
        rows.append((escape(name), f"{b['load_N']:.4g}", _um(_norm(b["deflection_m"])),
                     f"{eig[-1]:.3g} / {eig[-2]:.3g}", contact))  # fmt: skip
    if rows:
        t = Table(title="Load-dependent bearings at the operating point")
        for col in ("bearing", "load (N)", "deflection", "stiffness (N/m, principal)", "contact"):
            t.add_column(col)
        for r in rows:
            t.add_row(*r)
        console.print(t)
    if op["meshes"]:
        t = Table(title="Load-dependent meshes at the operating point")
        for col in ("mesh", "force (N)", "deflection", "stiffness (N/m)", "x nominal"):
            t.add_column(col)
        for name, m in op["meshes"].items():
            t.add_row(escape(name), f"{m['force_N']:.4g}", _um(m["deflection_m"]),
                      f"{m['stiffness_N_per_m']:.4g}",
                      f"{m['stiffness_N_per_m'] / m['nominal_N_per_m']:.3g}")  # fmt: skip
        console.print(t)
    for note in op.get("notes", []):
        console.print(f"[yellow]warning:[/yellow] {escape(note)}")


def _norm(v: Any) -> float:
    return math.sqrt(sum(float(x) ** 2 for x in v))


def _principal(K: list[list[float]]) -> list[float]:
    """Eigenvalues of the symmetric part of a 3x3 stiffness (bearing plane and axis)."""
    A = np.asarray(K, dtype=float)
    return [float(x) for x in np.linalg.eigvalsh(0.5 * (A + A.T))]
