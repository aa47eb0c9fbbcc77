"""Floquet verdicts of models past the dense limit (the band method, docs/stability.md
section 8) beside their steady-state solve, in one process (not a test).

Rows, each a model at one speed: the assembly, the solve (``solve_point``, stability off,
the file's harmonics or ``--order``/``--max-order``) and the verdict (``rl.floquet`` of the
assembled system, default options), wall and CPU seconds, the verdict's stages (the band's
Arnoldi runs, the small-gain scans, the lattice search: the rest), the CPU ratio verdict /
solve, the verdict, the band (modes, ``kappa_C`` and its norm), the peak resident memory above the
process of the solve and of the verdict (blank stages: the dense method, below the band), and
how the solve went (method, gmres strategy, iterations, harmonics). A verdict that raises
(a model error, a memory refusal) is recorded in its row; the solve's figures stand.

* the example rotor on ``--rotor`` shaft nodes (``6 N`` DOF) at 3000 and 4220 rpm;
* the gearbox with every shaft element split (``--gearbox`` DOFs, rheolin.data.fine);
* ``--also-solve 2:138 3:200``: each gearbox row's solve again with those harmonic sets
  (closure order and largest order of the input speed), beside its verdict;
* ``--runup N``: the gearbox (``--runup-dof`` DOFs) over N speeds from 1000 to 5000 rpm, a
  solve and a verdict at each (a :class:`~rheolin.floquet.Continuation`), and the 200-speed
  map projected from them; ``--runup-speeds RPM...`` at those speeds instead (``--rotor
  --gearbox-speeds --gearbox 20000 --runup-speeds 2980 3000 3020``: three speeds 20 rpm
  apart, as in a 200-speed map, without the single-speed rows).

Usage::

    OPENBLAS_NUM_THREADS=1 python bench/large_stability.py --rotor 101 401 1001 \\
        --gearbox 20000 --out bench/results/large_stability.md
"""

from __future__ import annotations

import argparse
import gc
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import rheolin as rl
from _memory import reset_peak, status_kb
from rheolin.budget import MemoryBudgetError
from rheolin.data.fine import refined_example
from rheolin.errors import ModelError
from rheolin.floquet import Continuation
from rheolin.io import parse_model
from rheolin.results.compute import solve_point

RPM = np.pi / 30


def timed(fn: Any) -> tuple[Any, float, float, float]:
    """``(result, wall s, cpu s, peak MB above the process)``."""
    gc.collect()
    base = status_kb("VmRSS")
    reset_peak()
    t, c = time.perf_counter(), time.process_time()
    out = fn()
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    return out, wall, cpu, max(status_kb("VmHWM") - base, 0) / 1024


#: CPU seconds of the last row's verdict (for the extra solves of ``--also-solve``).
LAST_VERDICT: dict[str, float] = {}


def also_solve(text: str, rpm: float, sets: list[str]) -> list[str]:
    """The model's solve with each of ``sets`` (``ORDER:MAX_ORDER``, ``MAX_ORDER`` ``none``:
    uncapped) beside the last row's verdict: harmonics, CPU s, peak MB, verdict / solve. A
    solve the memory budget refuses is recorded as such."""
    model = parse_model(text).model
    verdict = LAST_VERDICT.get("cpu", float("nan"))
    lines = []
    for spec in sets:
        o_text, _, mo_text = spec.partition(":")
        o, mo = int(o_text), (None if mo_text in ("", "none") else float(mo_text))
        gc.collect()
        try:
            point, _, cpu, peak = timed(
                lambda o=o, mo=mo: solve_point(
                    model, rpm * RPM, order=o, max_order=mo, stability=False
                )
            )
        except Exception as exc:  # a refusal (memory, harmonics) is a result here
            lines.append(f"| - | {spec} | - | - | - | {type(exc).__name__}: {str(exc)[:120]} |")
            print(lines[-1], flush=True)
            continue
        sol = point.solution
        n = point.assembled.system.n
        ok = "" if sol.success else ", failed"
        lines.append(
            f"| {n:,} | {spec} | {sol.harmonics.size} | {cpu:.2f} | {peak:.0f} | "
            f"{verdict / max(cpu, 1e-9):.2f}{ok} |"
        )
        print(lines[-1], flush=True)
    return lines


def row(name: str, text: str, rpm: float, order: int | None, max_order: float | None) -> str:
    lm = parse_model(text)
    model = lm.model
    h = lm.spec.harmonics
    o = h.order if order is None else order
    mo = h.max_order if max_order is None else max_order
    _, _, a_cpu, _ = timed(lambda: model.speed_template().assemble(rpm * RPM))
    point, s_wall, s_cpu, s_peak = timed(
        lambda: solve_point(model, rpm * RPM, order=o, max_order=mo, stability=False)
    )
    system = point.assembled.system
    sol = point.solution
    how = (
        f"{sol.method} {sol.info.get('strategy', '')}, {sol.iterations} its, "
        f"{sol.harmonics.size} harmonics" + ("" if sol.success else ", failed")
    )
    solved = f"| {name} | {system.n:,} | {rpm:g} | {a_cpu:.2f} | {s_wall:.2f} / {s_cpu:.2f} | "
    try:
        res, f_wall, f_cpu, peak = timed(lambda: rl.floquet(system))
    except (ModelError, MemoryBudgetError) as exc:  # recorded: the solve's figures stand
        failed = f"{type(exc).__name__}: {str(exc)[:160]}"
        line = solved + f"- | - | - | - | - | {failed} | - | - | - | {s_peak:.0f} | - | {how} |"
        print(line, flush=True)
        return line
    band = res.info.get("band") or {}
    beta = f", beta* {band['beta']:.2g}" if "beta" in band else ""
    stages = band.get("cpu") or {}
    arnoldi, scan = stages.get("arnoldi", float("nan")), stages.get("scan", float("nan"))
    search = f_cpu - (arnoldi + scan if stages else 0.0)
    LAST_VERDICT["cpu"] = f_cpu
    verdict = ("stable" if res.stable else "unstable") + ("" if res.decided else ", undecided")
    line = solved + (
        f"{f_wall:.2f} / {f_cpu:.2f} | {arnoldi:.2f} | {scan:.2f} | {search:.2f} | "
        f"{f_cpu / max(s_cpu, 1e-9):.2f} | {verdict} | {res.max_real:.6g} | "
        f"{band.get('modes', '-')} | {band.get('kappa', float('nan')):.3g} "
        f"{'(' + band['norm'] + ')' if 'norm' in band else ''}"
        f"{beta} | "
        f"{s_peak:.0f} | {peak:.0f} | {how} |"
    )
    print(line, flush=True)
    return line


def runup(text: str, speeds: np.ndarray, order: int, max_order: float) -> str:
    """A run-up as a stability map computes it: at every speed the steady-state solve (warm
    started from the previous speed's solution) and the verdict with a continuation; per-speed
    CPU seconds, the verdicts, and the 200-speed map projected from the medians."""
    model = parse_model(text).model
    template = model.speed_template()
    cont = Continuation()
    solve_cpu, cpu, decided, unstable, peaks = [], [], 0, 0, [0.0, 0.0]
    previous = None
    for rpm in speeds:
        point, _, s_cpu, s_peak = timed(
            lambda rpm=rpm, previous=previous: solve_point(
                model,
                rpm * RPM,
                order=order,
                max_order=max_order,
                stability=False,
                template=template,
                x0=previous,
            )
        )
        previous = point.solution
        system = point.assembled.system
        res, _, f_cpu, f_peak = timed(lambda system=system: rl.floquet(system, continuation=cont))
        solve_cpu.append(s_cpu)
        cpu.append(f_cpu)
        peaks = [max(peaks[0], s_peak), max(peaks[1], f_peak)]
        decided += int(res.decided)
        unstable += int(not res.stable)
        print(
            f"  {rpm:.1f} rpm: solve {s_cpu:.2f} s ({point.solution.iterations} its), verdict "
            f"{res.max_real:.5g} decided {res.decided} {f_cpu:.2f} s",
            flush=True,
        )
    per_speed = float(np.median(solve_cpu) + np.median(cpu))
    return (
        f"Run-up of the {system.n:,}-DOF gearbox over {len(speeds)} speeds "
        f"({speeds[0]:g}-{speeds[-1]:g} rpm), solves warm-started from the previous speed, "
        f"verdicts with a continuation: {decided} decided, {unstable} unstable; CPU per speed "
        f"median solve {np.median(solve_cpu):.2f} s (first {solve_cpu[0]:.2f} s), median verdict "
        f"{np.median(cpu):.2f} s (first {cpu[0]:.2f} s), total {sum(solve_cpu) + sum(cpu):.0f} s; "
        f"peak memory above the process: solves {peaks[0]:.0f} MB, verdicts {peaks[1]:.0f} MB. "
        "A 200-speed map at these medians: "
        f"{200 * per_speed:.0f} CPU s, {200 * per_speed / 2 / 60:.1f} min on 2 cores.\n"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rotor", type=int, nargs="*", default=[401], help="shaft nodes (odd)")
    ap.add_argument("--gearbox", type=int, nargs="*", default=[], help="DOFs")
    ap.add_argument("--gearbox-speeds", type=float, nargs="*", default=[3000.0])
    ap.add_argument("--order", type=int, default=2, help="gearbox solve: closure order")
    ap.add_argument("--max-order", type=float, default=60.0, help="gearbox solve: cut-off")
    ap.add_argument("--runup", type=int, default=0, help="gearbox run-up speeds (0: none)")
    ap.add_argument("--runup-dof", type=int, default=None, help="run-up DOFs (first --gearbox)")
    ap.add_argument("--runup-speeds", type=float, nargs="*", default=[],
                    help="the run-up's speeds [rpm] (instead of --runup's 1000-5000)")  # fmt: skip
    ap.add_argument("--also-solve", nargs="*", default=[], metavar="ORDER:MAX_ORDER",
                    help="gearbox rows: the solve again with these harmonic sets, beside the "
                    "verdict (e.g. 2:138 3:200)")  # fmt: skip
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    head = (
        "| model | DOF | rpm | assembly CPU s | solve s (wall / CPU) | verdict s (wall / CPU) | "
        "band Arnoldi CPU s | scan CPU s | lattice search CPU s | CPU ratio | verdict | "
        "largest real part 1/s | band modes | kappa_C, beta* | solve peak MB | verdict peak MB | "
        "solve |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    )
    print(head, end="")
    threads = " ".join(
        f"{k}={os.environ[k]}"
        for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
        if k in os.environ
    )
    command = f"{threads} python bench/large_stability.py " + " ".join(sys.argv[1:])
    rows: list[str] = []
    extra: list[str] = []

    def write(tail: str = "") -> str:
        """The results so far (written after every row: a run cut short keeps its rows)."""
        others = ""
        if extra:
            others = (
                "The verdict of each gearbox row beside the solve of the same model with other "
                "harmonic sets (`--also-solve`; closure order : largest order of the input "
                "speed):\n\n| DOF | order : max order | harmonics | solve CPU s | solve peak MB "
                "| verdict / solve |\n|---|---|---|---|---|---|\n" + "\n".join(extra) + "\n\n"
            )
        text = (
            "# Floquet verdicts past the dense limit\n\n"
            f"`{command}`, one process on a shared 2-core machine (wall times vary with the "
            "load; CPU times are this process's).\n\n"
            + head
            + "\n".join(rows)
            + "\n\n"
            + others
            + tail
        )
        if args.out:
            Path(args.out).write_text(text)
        return text

    for nodes in args.rotor:
        for rpm in (3000.0, 4220.0):
            rows.append(
                row(f"rotor, {nodes} nodes", refined_example("rotor", nodes), rpm, None, None)
            )
            write()
    for dof in args.gearbox:
        text = refined_example("gearbox", dof=dof)
        for rpm in args.gearbox_speeds:
            rows.append(row("gearbox, fine shafts", text, rpm, args.order, args.max_order))
            if args.also_solve:
                extra += also_solve(text, rpm, args.also_solve)
            write()
    tail = ""
    if (args.runup or args.runup_speeds) and args.gearbox:
        speeds = np.asarray(args.runup_speeds or np.linspace(1000.0, 5000.0, args.runup))
        dof = args.runup_dof or args.gearbox[0]
        tail = runup(refined_example("gearbox", dof=dof), speeds, args.order, args.max_order)
    print(write(tail))
    if args.out:
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
