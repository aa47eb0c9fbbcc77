"""The run-up across the gear variant's principal range for bench/stability.py, section (d):
the worker (``runup``), its report section (``runup_lines``) and the rewrite of that section
alone in an existing results file (``splice``)."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
RPM = np.pi / 30


def _variant():  # type: ignore[no-untyped-def]
    sys.path.insert(0, str(HERE.parent / "tests" / "stability"))
    from gear_variants import reference_ranges, variant_document, variant_model

    return variant_model(), variant_document()["harmonics"], reference_ranges()


def runup(step: float) -> dict:
    import rheolin as rl
    from rheolin.floquet import Continuation
    from rheolin.results.compute import solve_point
    from rheolin.stability import stability_map
    from rheolin.study.run import MAP_PRECISION

    model, harm, ref = _variant()
    edges = ref["ranges"]["principal"]
    lo, hi = edges["lower_rpm"], edges["upper_rpm"]
    opts = {"order": harm["order"], "max_order": harm["max_order"], "stability": False}
    solve_point(model, 3000 * RPM, **opts)  # warm-up
    cont = Continuation()
    previous = None
    rows = []
    for rpm in np.arange(3200.0, 4100.0 + step / 2, step):
        c = time.process_time()
        p = solve_point(model, rpm * RPM, x0=previous, **opts)
        solve = time.process_time() - c
        previous = p.solution if p.solution.success else None
        c = time.process_time()
        res = rl.floquet(p.assembled.system, continuation=cont)
        verdict = time.process_time() - c
        where = (
            "inside"
            if lo < rpm < hi
            else ("near" if min(abs(rpm - lo), abs(rpm - hi)) <= 100 else "far")
        )
        rows.append(
            {
                "rpm": float(rpm),
                "solve": solve,
                "verdict": verdict,
                "where": where,
                "decided": bool(res.decided),
                "stable": bool(res.stable),
                "max_real": float(res.max_real),
                "uncertainty": float(res.max_real_uncertainty),
                "order": res.lattice.order if res.lattice is not None else None,
                # the finest lattice any of its exponents comes from (confirmations included)
                "finest": int(np.max(res.info["order"])) if res.exponents.size else None,
                "accuracy": res.info.get("accuracy", {}).get("orders"),
            }
        )
    samples = np.arange(3300.0, 4000.0 + 1.0, 100.0)
    c = time.process_time()
    smap = stability_map(model, samples * RPM, refine=MAP_PRECISION, rtol=np.inf)
    map_cpu = time.process_time() - c
    (r,) = smap.ranges
    return {
        "rows": rows,
        "map_cpu": map_cpu,
        "map_evaluations": smap.info.get("evaluations"),
        "bounds": {
            "lower": [r.lower / RPM, r.lower_uncertainty / RPM, lo, edges["lower_uncertainty_rpm"]],
            "upper": [r.upper / RPM, r.upper_uncertainty / RPM, hi, edges["upper_uncertainty_rpm"]],
        },
        "states": smap.state.tolist(),
    }


def runup_lines(u: dict) -> list[str]:
    rows = u["rows"]
    ratios = np.array([r["verdict"] / r["solve"] for r in rows])
    worst = rows[int(np.argmax(ratios))]
    median_solve = float(np.median([r["solve"] for r in rows]))
    lines = [
        "",
        "## Run-up across an unstable range (gear variant, 72 DOFs, 3200-4100 rpm every 25 rpm)",
        "",
        "`OPENBLAS_NUM_THREADS=1 python bench/stability.py --sections runup "
        "--out bench/results/stability.md` (rewrites this section only).",
        "",
        "Principal parametric resonance of the polymer second mesh, unstable 3439.46-3877.13 rpm "
        "(monodromy matrix). Per speed, CPU seconds; the verdict continued from the previous "
        "speed as in a sweep, the solve from the previous solution; near: within 100 rpm of an "
        "edge.",
        "",
        "| where | speeds | solve [s] median | verdict [s] median / max | verdict / solve max | "
        "decided | lattice order |",
        "|---|---|---|---|---|---|---|",
    ]
    for where in ("far", "near", "inside"):
        sel = [r for r in rows if r["where"] == where]
        if not sel:
            continue
        solve = np.array([r["solve"] for r in sel])
        verdict = np.array([r["verdict"] for r in sel])
        ratio = verdict / solve
        orders = sorted({r["order"] for r in sel})
        lines.append(
            f"| {where} | {len(sel)} | {np.median(solve):.2f} | {np.median(verdict):.2f} / "
            f"{verdict.max():.2f} | {ratio.max():.1f}x | "
            f"{sum(r['decided'] for r in sel)} of {len(sel)} | "
            f"{', '.join(str(o) for o in orders)} |"
        )
    lines += [
        "",
        f"Worst ratio **{ratios.max():.1f}x** at {worst['rpm']:.0f} rpm (verdict "
        f"{worst['verdict']:.2f} s, solve {worst['solve']:.2f} s); against the median solve "
        f"({median_solve:.2f} s) the dearest verdict is "
        f"{max(r['verdict'] for r in rows) / median_solve:.1f}x.",
        "",
        "Per speed within 100 rpm of an edge and inside (lattice order of the verdict, and the "
        "finest order its exponents come from, confirmations included):",
        "",
        "| rpm | solve [s] | verdict [s] | ratio | order / finest | largest real part [1/s] |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        if r["where"] == "far":
            continue
        state = "" if r["decided"] else " (undecided)"
        lines.append(
            f"| {r['rpm']:.0f} | {r['solve']:.2f} | {r['verdict']:.2f} | "
            f"{r['verdict'] / r['solve']:.1f}x | {r['order']} / {r['finest']} | "
            f"{r['max_real']:+.5f} +- {r['uncertainty']:.2g}{state} |"
        )
    lines += [
        "",
        f"Map from samples every 100 rpm (3300-4000 rpm), bounds refined to 1e-5 by decided "
        f"verdicts: {u['map_cpu']:.1f} CPU s, {u['map_evaluations']} Floquet evaluations "
        "for the two edges.",
        "",
        "| edge | map [rpm] | stated uncertainty [rpm] | monodromy [rpm] | error | relative |",
        "|---|---|---|---|---|---|",
    ]
    for side in ("lower", "upper"):
        got, unc, ref, ref_unc = u["bounds"][side]
        lines.append(
            f"| {side} | {got:.6f} | {unc:.2g} | {ref:.6f} (+-{ref_unc:.1g}) | "
            f"{got - ref:+.2g} | {abs(got - ref) / ref:.1e} |"
        )
    return lines


def splice(old: str, section: list[str]) -> str:
    """``old`` with its section of the same heading as ``section`` replaced (appended when
    it has none): a run of some sections keeps the others' figures."""
    heading = next(line for line in section if line.startswith("## "))
    key = heading.split("(")[0]
    lines = old.rstrip("\n").split("\n")
    start = next((i for i, line in enumerate(lines) if line.startswith(key)), None)
    body = section[section.index(heading) :]
    if start is None:
        return "\n".join([*lines, "", *body]) + "\n"
    end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("## ")), len(lines))
    tail = lines[end:]
    return "\n".join([*lines[:start], *body, *([""] if tail else []), *tail]) + "\n"
