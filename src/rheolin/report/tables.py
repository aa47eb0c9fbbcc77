"""The report's tables, as HTML: verdicts with their uncertainty, critical speeds, resonances
with amplification factors and API 617 separation margins, unstable ranges with their
bounds and mechanisms, the preloaded operating point, and the inputs for traceability.
Every text from the results (names, messages) is escaped.

>>> print(table(["a", "b"], [["1", "<x>"]]))
<table><thead><tr><th>a</th><th>b</th></tr></thead><tbody><tr><td>1</td><td>&lt;x&gt;</td></tr></tbody></table>
"""

from __future__ import annotations

import html
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..results.api684 import MIN_BAND_SAMPLES, separation_margin

__all__ = [
    "badge",
    "critical_speed_rows",
    "fmt",
    "operating_point_rows",
    "range_rows",
    "resonance_rows",
    "table",
    "verdict_rows",
]

RPM = 30 / math.pi


def fmt(x: Any, spec: str = ".4g", missing: str = "n/a") -> str:
    """``format(x, spec)``; ``missing`` for None and NaN; text as it is.

    >>> fmt(1500.0000000000002, ".6g"), fmt(None), fmt(float("nan"))
    ('1500', 'n/a', 'n/a')
    """
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return missing
    if isinstance(x, str):
        return x
    return format(x, spec)


def table(head: Sequence[str], rows: Sequence[Sequence[Any]], cls: str = "") -> str:
    """An HTML table; every cell escaped (a cell given as ``("html", text)`` is not)."""

    def cell(c: Any, tag: str) -> str:
        if isinstance(c, tuple) and c and c[0] == "html":
            return f"<{tag}>{c[1]}</{tag}>"
        return f"<{tag}>{html.escape(str(c))}</{tag}>"

    attr = f' class="{cls}"' if cls else ""
    body = "".join("<tr>" + "".join(cell(c, "td") for c in r) + "</tr>" for r in rows)
    return (
        f"<table{attr}><thead><tr>{''.join(cell(h, 'th') for h in head)}</tr></thead>"
        f"<tbody>{body}</tbody></table>"
    )


def badge(text: str, kind: str) -> tuple[str, str]:
    """A coloured verdict word (``ok``, ``bad``, ``warn``) as an HTML cell."""
    return ("html", f'<span class="badge {kind}">{html.escape(text)}</span>')


def verdict_rows(summary: dict[str, Any]) -> list[list[Any]]:
    """One operating point's verdict: convergence, residual, stability and its uncertainty."""
    stab = str(summary.get("stability"))
    ok = bool(summary.get("success"))
    decided = summary.get("stability_decided")
    lead = summary.get("leading_exponent_frequency_hz")
    solver = f"{summary.get('method')} ({summary.get('iterations')} iterations)"
    residual = (
        f"tolerance {fmt(summary.get('rtol'), '.0e')}; ||f - A q|| / ||f|| = "
        f"{fmt(summary.get('relative_residual'), '.2e')}"
    )
    floquet = f"largest real part {fmt(summary.get('max_floquet_real'), '.4g')} 1/s"
    if lead is not None:
        floquet += f" at {fmt(lead, '.5g')} Hz"
    if summary.get("floquet_method"):
        floquet += f"; {summary['floquet_method']} Hill"
        if summary.get("floquet_lattice_order") is not None:
            floquet += (
                f", lattice order {summary['floquet_lattice_order']} "
                f"({summary.get('floquet_lattice_size')} harmonics)"
            )
    why = {
        True: "the truncation cannot flip it",
        False: "the truncation could still flip it (docs/stability.md)",
        None: "",
    }[decided]
    word = {True: "yes", False: "NO", None: "not checked"}[decided]
    rows: list[list[Any]] = [
        ["converged", badge("yes" if ok else "NO", "ok" if ok else "bad"),
         f"{solver}; {summary.get('message')}"],
        ["backward error", fmt(summary.get("residual"), ".2e"), residual],
        ["stability (Floquet)",
         badge(stab, {"stable": "ok", "unstable": "bad"}.get(stab, "warn")), floquet],
        ["verdict decided", badge(word, "ok" if decided else "warn"), why],
    ]  # fmt: skip
    if summary.get("stability_mechanism"):
        rows.append(["mechanism", summary["stability_mechanism"], ""])
    return rows


def operating_point_rows(op: dict[str, Any]) -> list[list[Any]]:
    """The preloaded operating point: each load-dependent bearing's load, deflection and
    operating stiffness, each mesh's force and stiffness, the torques."""
    rows: list[list[Any]] = []
    for name, b in op.get("bearings", {}).items():
        K = np.asarray(b["stiffness_N_per_m"], dtype=float)
        k = np.sort(np.abs(np.linalg.eigvalsh(0.5 * (K + K.T))))[::-1]
        contact = (
            f"{b['in_contact']} of {b['elements']}" if b.get("elements") else str(b["in_contact"])
        )
        rows.append(
            [
                f"bearing {name}",
                f"{b['load_N']:.4g} N",
                f"{np.linalg.norm(b['deflection_m']) * 1e6:.3g} µm",
                f"{k[0]:.3g} / {k[1]:.3g} N/m",
                contact,
            ]
        )
    for name, m in op.get("meshes", {}).items():
        rows.append(
            [
                f"mesh {name}",
                f"{m['force_N']:.4g} N",
                f"{m['deflection_m'] * 1e6:.3g} µm",
                f"{m['stiffness_N_per_m']:.4g} N/m "
                f"({m['stiffness_N_per_m'] / m['nominal_N_per_m']:.3g} x nominal)",
                "",
            ]
        )
    for name, t in op.get("torques_N_m", {}).items():
        rows.append([f"torque {name}", f"{t:.6g} N m", "", "", ""])
    return rows


def critical_speed_rows(cds: Any) -> list[list[Any]]:
    """The Campbell diagram's critical speeds (order-line crossings), by speed."""
    rows = []
    n = cds.sizes.get("critical", 0)
    for k in range(n):
        rows.append(
            [
                str(cds["critical_order"].values[k]),
                int(cds["critical_mode"].values[k]),
                str(cds["critical_kind"].values[k] or cds["critical_whirl"].values[k]),
                fmt(float(cds["critical_speed"].values[k]) * RPM, ".1f"),
                fmt(float(cds["critical_frequency"].values[k]), ".2f"),
            ]
        )
    return rows


def resonance_rows(
    resonances: list[dict[str, Any]], operating_rpm: tuple[float, float] | None
) -> list[list[Any]]:
    """Resonances of a run-up with their half-power AF, its resolution (speeds inside the
    band), and with an operating range the separation margin and API 617's requirement."""
    rows = []
    for p in resonances:
        af = p.get("amplification_factor")
        n = p.get("samples_in_band")
        resolved = p.get("resolved")
        res: Any = ""
        if n is not None:
            coarse = f"{n} speeds (< {MIN_BAND_SAMPLES}: coarse)"
            res = badge(f"{n} speeds", "ok") if resolved else badge(coarse, "warn")
        margin: Any = ""
        required: Any = ""
        verdict: Any = ""
        if operating_rpm is not None:
            m, req = separation_margin(float(p["speed_rpm"]), af, operating_rpm)
            margin, required = f"{100 * m:.1f} %", f"{100 * req:.1f} %"
            verdict = badge("meets", "ok") if m >= req else badge("too close", "bad")
        band = p.get("half_power_rpm")
        rows.append(
            [
                p["body"],
                p.get("node", ""),
                fmt(p["speed_rpm"], ".6g"),
                fmt(p["amplitude_m"] * 1e6, ".3g"),
                fmt(af, ".3g"),
                "" if band is None else f"{band[0]:.6g} to {band[1]:.6g}",
                res,
                margin,
                required,
                verdict,
            ]
        )
    return rows


def range_rows(ranges: list[dict[str, Any]]) -> list[list[Any]]:
    """Unstable speed ranges (``sweep.json`` entries or the map's): bounds, whether they
    reach the end of the sweep, the largest real part and the mechanism."""
    rows = []
    for r in ranges:
        lo = ("< " if r.get("open_below") else "") + fmt(r["lower_rpm"], ".6g")
        hi = fmt(r["upper_rpm"], ".6g") + (" >" if r.get("open_above") else "")
        params = ", ".join(f"{k} = {v}" for k, v in (r.get("parameters") or {}).items())
        rows.append(
            [
                lo,
                hi,
                fmt(r.get("max_real_per_s"), ".3g"),
                r.get("mechanism", ""),
                r.get("label", ""),
                params,
            ]
        )
    return rows
