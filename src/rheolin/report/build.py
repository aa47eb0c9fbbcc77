"""Build the report of a result directory: the sections each kind of result contributes."""

from __future__ import annotations

import html
import math
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..io.atomic import atomic_write
from . import figures
from .collect import ResultDirectory, file_digests, read_directory
from .page import Page
from .tables import (
    badge,
    critical_speed_rows,
    fmt,
    operating_point_rows,
    range_rows,
    resonance_rows,
    table,
    verdict_rows,
)

__all__ = ["REPORT_FILE", "build_report", "write_report"]

#: The report's file name in its result directory.
REPORT_FILE = "report.html"
RPM = 30 / math.pi


#: What a result file not as rheolin writes it raises in a section builder.
MALFORMED = (KeyError, TypeError, AttributeError, ValueError, IndexError)


def _notes(d: ResultDirectory) -> str:
    notes = list(d.notes)
    for name in ("summary.json", "sweep.json"):
        warned = d.tables.get(name, {}).get("warnings", [])
        notes += [str(w) for w in warned] if isinstance(warned, list) else [str(warned)]
    if not notes:
        return ""
    items = "".join(f"<li>{html.escape(n)}</li>" for n in dict.fromkeys(notes))
    return f'<div class="notes"><b>Read first</b><ul>{items}</ul></div>'


def _model_section(page: Page, d: ResultDirectory, nodes: bool) -> None:
    if d.model is None or d.model_path is None:
        return
    from ..plots.drawing import model_figure

    spec = d.model.spec.model
    m = d.model.model
    info = [
        ["model file", str(d.model_path)],
        ["name", spec.name or ""],
        ["description", getattr(spec, "description", "") or ""],
        [
            "bodies",
            ", ".join(
                f"{b} ({m.bodies[b].kind}, {len(m.bodies[b].positions)} nodes)" for b in m.bodies
            ),
        ],
        ["bearings, couplings", ", ".join([*m.joints, *m.rolling]) or "none"],
        ["gear meshes", ", ".join(m.meshes) or "none"],
    ]
    fig = model_figure(m, nodes=nodes, title=f"{spec.name or d.model_path.name}")
    page.section("model", "Model", table(["", ""], info) + page.svg(fig))


def _run_sections(page: Page, d: ResultDirectory) -> None:
    s = d.tables.get("summary.json")
    ds = d.datasets.get("results.nc")
    if s:
        page.section(
            "verdict",
            f"Operating point at {fmt(s.get('speed_rpm'), '.6g')} rpm",
            table(["", "verdict", "detail"], verdict_rows(s)),
        )
        if s.get("operating_point"):
            op = s["operating_point"]
            head = (
                f"<p>Static equilibrium under the torques and static loads (the dynamics is "
                f"solved about it): largest deflection {op['max_displacement_m'] * 1e6:.3g} µm at "
                f"{html.escape(str(op['max_displacement_at']['body']))} node "
                f"{op['max_displacement_at']['node']}; {op['iterations']} Newton iterations.</p>"
            )
            page.section(
                "operating-point",
                "Preloaded operating point",
                head
                + table(
                    ["item", "load", "deflection", "operating stiffness (principal)", "contact"],
                    operating_point_rows(op),
                ),
            )
    if ds is not None:
        body = page.figure(figures.spectrum_figure(ds)) + page.figure(figures.orbit_figure(ds))
        if "bearing_force" in ds:
            body += page.figure(figures.bearing_figure(ds))
        page.section("response", "Response", body + _largest(s))


def _largest(s: dict[str, Any] | None) -> str:
    if not s:
        return ""
    rows = [
        [
            b,
            v["node"],
            fmt(v["static_radial_m"] * 1e6, ".3g"),
            fmt(v["radial_amplitude_bound_m"] * 1e6, ".3g"),
            "; ".join(
                f"{h['amplitude'] * 1e6:.3g} µm at {h['frequency_hz']:.5g} Hz"
                for h in v["largest_harmonics"][:3]
            ),
        ]
        for b, v in s.get("bodies", {}).items()
    ]
    out = table(["body", "node", "static [µm]", "dynamic, sum [µm]", "largest harmonics"], rows)
    if s.get("bearings"):
        rows = [
            [
                b,
                fmt(v["static_radial_N"], ".4g"),
                fmt(v["dynamic_radial_sum_N"], ".4g"),
                "; ".join(
                    f"{h['amplitude']:.3g} N at {h['frequency_hz']:.5g} Hz"
                    for h in v["largest_harmonics"][:2]
                ),
            ]
            for b, v in s["bearings"].items()
        ]
        out += table(["bearing", "static radial [N]", "dynamic radial, sum [N]", "largest"], rows)
    return out


def _map_summary(sds: Any) -> str:
    """The stability verdicts over speed and their uncertainty."""
    n = sds.sizes["speed"]
    stable = sds["stable"].values.astype(bool)
    decided = sds["decided"].values.astype(bool) if "decided" in sds else np.ones(n, bool)
    tol = sds["tol"].values
    rows = [
        ["speeds checked", n],
        ["unstable", badge(str(int((~stable).sum())), "bad" if (~stable).any() else "ok")],
        [
            "undecided (the truncation could flip the verdict)",
            badge(str(int((~decided).sum())), "warn" if (~decided).any() else "ok"),
        ],
        ["largest real part", f"{np.nanmax(sds['max_real'].values):.4g} 1/s"],
        ["decision tolerance (largest)", f"{np.nanmax(tol):.2g} 1/s"],
    ]
    return table(["Floquet stability map", ""], rows)


def _ranges(d: ResultDirectory) -> list[dict[str, Any]]:
    sweep = d.tables.get("sweep.json")
    if sweep is not None:
        return list(sweep.get("unstable_ranges", []))
    sds = d.datasets.get("stability_map.nc")
    if sds is None or "range_lower" not in sds:
        return []
    return [
        {
            "lower_rpm": lo * RPM,
            "upper_rpm": hi * RPM,
            "open_below": bool(a),
            "open_above": bool(b),
            "max_real_per_s": float(m),
            "mechanism": str(mech),
            "label": str(label),
        }
        for lo, hi, a, b, m, mech, label in zip(
            sds["range_lower"].values,
            sds["range_upper"].values,
            sds["range_lower_open"].values,
            sds["range_upper_open"].values,
            sds["range_max_real"].values,
            sds["range_mechanism"].values,
            sds["range_label"].values,
            strict=True,
        )
    ]


def _stability_sections(page: Page, d: ResultDirectory) -> None:
    sds = d.datasets.get("stability_map.nc")
    ranges = _ranges(d)
    body = ""
    if sds is not None and "speed" in sds.dims and "max_real" in sds:
        body += _map_summary(sds)
        if sds["max_real"].dims == ("speed",):  # a parameter study's maps: its PNGs show them
            body += page.figure(figures.stability_figure(sds))
    head = [
        "from [rpm]",
        "to [rpm]",
        "largest real part [1/s]",
        "mechanism",
        "detail",
        "parameters",
    ]
    if ranges:
        body += "<h3>Unstable speed ranges</h3>" + table(head, range_rows(ranges))
    elif sds is not None:
        body += "<p>No unstable speed range.</p>"
    page.section("stability", "Stability over speed", body)


def _sweep_sections(page: Page, d: ResultDirectory, operating: tuple[float, float] | None) -> None:
    ds = d.datasets.get("sweep.nc")
    sweep = d.tables.get("sweep.json", {})
    if ds is None or "response" not in ds or "speed_rpm" not in ds.coords:
        return
    if ds["response"].dims[0] != "speed":  # a parameter study: its PNGs show it
        return
    peaks = list(sweep.get("resonances", []))
    ranges = [(r["lower_rpm"], r["upper_rpm"]) for r in sweep.get("unstable_ranges", [])]
    body = page.figure(figures.sweep_figure(ds, peaks, ranges))
    body += page.figure(figures.waterfall_figure(ds))
    if peaks:
        where = (
            ""
            if operating is None
            else f"; separation margins from the operating range {operating[0]:.6g} to "
            f"{operating[1]:.6g} rpm (API 617)"
        )
        body += f"<h3>Resonances (half-power amplification factor, API 684{where})</h3>"
        body += table(
            [
                "body",
                "node",
                "speed [rpm]",
                "amplitude [µm]",
                "AF",
                "half-power band [rpm]",
                "speeds in band",
                "margin",
                "required",
                "API 617",
            ],
            resonance_rows(peaks, operating),
        )
    page.section("run-up", "Response over speed", body)


def _campbell_sections(page: Page, d: ResultDirectory) -> None:
    cds = d.datasets.get("campbell.nc")
    if cds is None:
        return
    body = page.figure(figures.campbell_figure(cds))
    rows = critical_speed_rows(cds)
    if rows:
        body += "<h3>Critical speeds (order-line crossings)</h3>" + table(
            ["order line", "branch", "kind", "speed [rpm]", "frequency [Hz]"], rows
        )
    page.section("campbell", "Campbell diagram and critical speeds", body)


def _modes_sections(page: Page, d: ResultDirectory) -> None:
    mds = d.datasets.get("modes.nc")
    if mds is not None:
        rows = [
            [int(m), f"{f:.3f}", f"{z:.4g}", str(k)]
            for m, f, z, k in zip(
                mds["mode"].values,
                mds["frequency"].values,
                mds["damping_ratio"].values,
                mds["kind"].values,
                strict=True,
            )
        ]
        page.section(
            "modes",
            f"Modes at {fmt(mds.attrs.get('speed_rpm'), '.6g')} rpm",
            table(["mode", "frequency [Hz]", "damping ratio", "kind"], rows),
        )
    fds = d.datasets.get("frf.nc")
    if fds is not None:
        from ..results.frf import FrequencyResponse

        page.section(
            "frf",
            "Frequency response",
            page.figure(figures.bode_figure(FrequencyResponse.from_dataset(fds))),
        )


def _inputs_section(page: Page, d: ResultDirectory, operating: Any) -> None:
    recorded = str(d.recorded("model_sha256") or "")
    match = (
        ""
        if not d.model_sha256
        else (
            badge("matches the results", "ok")
            if d.model_sha256 == recorded or not recorded
            else badge("differs from the results'", "bad")
        )
    )
    rows: list[list[Any]] = [
        ["model file (as recorded)", str(d.recorded("model_file") or "not recorded")],
        ["model file SHA-256 (results)", recorded or "not recorded"],
        ["model file read for this report", str(d.model_path or "none")],
        [
            "its SHA-256 now",
            ("html", html.escape(d.model_sha256 or "") + " " + (match[1] if match else "")),
        ],
        ["rheolin version (results)", str(d.recorded("rheolin_version") or "not recorded")],
        ["rheolin version (report)", __version__],
    ]
    s = d.tables.get("summary.json", {})
    for key in (
        "method",
        "requested_method",
        "rtol",
        "closure_order",
        "max_order",
        "harmonic_count",
        "n_dof",
    ):
        if s.get(key) is not None:
            rows.append([key, str(s[key])])
    sweep = d.tables.get("sweep.json", {})
    if sweep:
        speeds = sweep.get("speeds_rpm", [])
        rows.append(
            [
                "speeds [rpm]",
                f"{len(speeds)} from {fmt(min(speeds, default=None), '.6g')} "
                f"to {fmt(max(speeds, default=None), '.6g')}",
            ]
        )
        rows.append(["study key", sweep.get("study_key", "")])
        for p in sweep.get("parameters", []):
            rows.append([f"varied: {p['path']}", f"{p['values']} {p['unit']}"])
    if operating is not None:
        rows.append(["operating range [rpm]", f"{operating[0]:.6g} to {operating[1]:.6g}"])
    files = table(["file", "bytes", "SHA-256"], [list(x) for x in file_digests(d)])
    page.section("inputs", "Inputs and files (traceability)", table(["", ""], rows) + files)


def build_report(
    d: ResultDirectory,
    operating_rpm: tuple[float, float] | None = None,
    nodes: bool = False,
    where: str | None = None,
) -> str:
    """The report page of result directory ``d`` (see :func:`read_directory`).
    ``operating_rpm``: the operating speed range for the separation margins (default: the
    model file's speed, as a range of one speed); ``where``: the directory's name in the
    title (default: its path)."""
    if operating_rpm is None and d.model is not None and d.model.spec.model.speed:
        w = float(d.model.spec.model.speed) * RPM
        operating_rpm = (w, w)
    name = d.model.spec.model.name if d.model is not None else ""
    title = f"rheolin report: {name or d.path.name}"
    page = Page(title, f"{', '.join(d.kinds) or 'no results'} in {where or d.path}")
    _guarded(page, d, _run_sections)
    if {"stability map", "sweep", "campbell"} & set(d.kinds):
        _guarded(page, d, _stability_sections)
    _guarded(page, d, _sweep_sections, operating_rpm)
    _guarded(page, d, _campbell_sections)
    _guarded(page, d, _modes_sections)
    _model_section(page, d, nodes)
    if d.images:
        pngs = "".join(
            f"<details><summary>{html.escape(n)}</summary>{page.png(n, b)}</details>"
            for n, b in d.images.items()
        )
        page.section("pictures", "Figures as files (PNG)", pngs)
    _guarded(page, d, _inputs_section, operating_rpm)
    notes = _notes(d)  # first, with what the sections found
    if notes:
        page.sections.insert(0, ("notes", "Notes", notes))
    return page.html()


def _guarded(page: Page, d: ResultDirectory, build: Any, *args: Any) -> None:
    """Add the sections of ``build``; result files that are not as rheolin writes them
    (edited, or another program's) leave them out, said in the notes, not a failed report."""
    before = len(page.sections)
    try:
        build(page, d, *args)
    except MALFORMED as exc:
        del page.sections[before:]
        what = build.__name__.strip("_").removesuffix("_sections").removesuffix("_section")
        files = ", ".join([*d.tables, *d.datasets])
        d.leave_out(
            f"the {what} part of the report is left out: the result files ({files}) are not "
            f"as rheolin writes them ({type(exc).__name__}: {exc})"
        )


def write_report(
    directory: str | Path,
    *,
    model: str | Path | None = None,
    operating_rpm: tuple[float, float] | None = None,
    nodes: bool = False,
    path: str | Path | None = None,
    where: str | None = None,
    left_out: list[str] | None = None,
) -> Path:
    """Write ``directory/report.html`` (or ``path``) atomically; returns its path. ``where``:
    the directory's name in the title (a command writing into a staging directory gives
    the final one); ``left_out``: a list that receives one line per part of the report left
    out (a result file that could not be used, and why)."""
    d = read_directory(directory, model)
    text = build_report(d, operating_rpm, nodes, where)
    out = Path(path) if path is not None else Path(directory) / REPORT_FILE
    with atomic_write(out) as tmp:
        tmp.write_text(text, encoding="utf-8")
    if left_out is not None:
        left_out.extend(d.left_out)
    return out
