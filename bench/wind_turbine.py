"""Wind-turbine benchmark: the drive train with a planetary stage (``rheolin example
wind-turbine``) against the two-stage gearbox, one run, ratios side by side (not a test).

What it measures (2 cores unless the machine has more):

1. one point of each model, serial, one BLAS thread (the wind turbine at 22.1 rpm, the gearbox
   at 3000 rpm, each with its file's harmonic settings): the steady-state solve and the Floquet
   verdict, each cold and per DOF, and their ratios (wind turbine / gearbox);
2. a stretch of each model's 1000-speed run-up as a study worker computes it (32 consecutive
   speeds from the middle of the grid, two continuation blocks of 16, serial): CPU seconds per
   point and their ratio; the 1000-speed run-up of the wind turbine (4..24 rpm) on 2 cores is
   estimated from its rate (marked "est.");
3. with ``--full``, the whole 1000-speed run-up on 2 worker processes (``LocalCluster``): wall
   time, the workers' CPU time, the verdicts.

Usage::

    python bench/wind_turbine.py [--full] [--out bench/results/wind_turbine.md]
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

RPM = np.pi / 30


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="write the results (markdown)")
    ap.add_argument("--full", action="store_true", help="also run the 1000-speed run-up")
    args = ap.parse_args()
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    from rheolin.data import example_path
    from rheolin.study import StudySpec

    lines: list[str] = []

    def say(text: str = "") -> None:
        print(text, flush=True)
        lines.append(text)

    load0 = os.getloadavg()
    say("# Wind-turbine drive train against the gearbox (bench/wind_turbine.py)")
    say()
    say(
        f"{os.cpu_count()} cores; load average {load0[0]:.2f} at the start (other work on the "
        "machine slows every number below alike)"
    )
    say()
    wt = _one_point("wind-turbine", 22.1 * RPM)
    gb = _one_point("gearbox", 3000 * RPM)
    say("## 1. One point, cold, serial, one BLAS thread")
    say()
    say("| model | DOF | harmonics | solve [s] | per DOF [ms] | verdict [s] | per DOF [ms] |")
    say("|---|---|---|---|---|---|---|")
    for name, p in (("wind turbine, 22.1 rpm", wt), ("gearbox, 3000 rpm", gb)):
        say(
            f"| {name} | {p['n']} | {p['harmonics']} | {p['solve']:.2f} | "
            f"{1e3 * p['solve'] / p['n']:.1f} | {p['floquet']:.2f} | "
            f"{1e3 * p['floquet'] / p['n']:.1f} |"
        )
    say()
    ratio_s = (wt["solve"] / wt["n"]) / (gb["solve"] / gb["n"])
    ratio_f = (wt["floquet"] / wt["n"]) / (gb["floquet"] / gb["n"])
    say(
        f"per-DOF cost, wind turbine / gearbox: steady state {ratio_s:.2f}x, verdict "
        f"{ratio_f:.2f}x (goal: at most 2x each); verdicts: wind turbine {wt['verdict']}, "
        f"gearbox {gb['verdict']}"
    )
    say()
    grids = {
        "wind-turbine": np.linspace(4.0, 24.0, 1000) * RPM,
        "gearbox": np.linspace(500.0, 6000.0, 1000) * RPM,
    }
    rate = {name: _stretch(name, grid) for name, grid in grids.items()}
    say("## 2. A stretch of each run-up: 32 consecutive speeds, as a study worker computes them")
    say()
    say("| model | grid | CPU per point [s] | per DOF [ms] |")
    say("|---|---|---|---|")
    for name, grid in grids.items():
        n = wt["n"] if name == "wind-turbine" else gb["n"]
        say(
            f"| {name} | {grid[0] / RPM:g}..{grid[-1] / RPM:g} rpm | {rate[name]:.2f} | "
            f"{1e3 * rate[name] / n:.1f} |"
        )
    say()
    est = 1000 * rate["wind-turbine"] / 2
    say(
        f"per point, wind turbine / gearbox: {rate['wind-turbine'] / rate['gearbox']:.2f}x; "
        f"1000-speed wind-turbine run-up on 2 cores, est.: {est:.0f} s = {est / 60:.1f} min of "
        "CPU per core (goal: at most 10 min)"
    )
    say()
    if args.full:
        whole = _run(StudySpec.create(example_path("wind-turbine"), grids["wind-turbine"]))
        say("## 3. The whole run-up: 1000 speeds, 4..24 rpm, 2 workers")
        say()
        say("| | value |")
        say("|---|---|")
        say(f"| wall, cluster start to results on disk | **{whole['wall']:.0f} s** |")
        say(f"| points phase | {whole['points']:.0f} s |")
        say(f"| CPU time of the workers | {whole['cpu']} s |")
        say(f"| verdicts | {whole['decided']} of 1000 decided, {whole['stable']} stable |")
        say(f"| unstable ranges | {whole['ranges'] or 'none'} |")
        say(f"| peak RSS per worker | {whole['rss']} MB |")
        say()
    load1 = os.getloadavg()
    say(f"load average {load1[0]:.2f} at the end")
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text("\n".join(lines) + "\n")


def _one_point(name: str, speed: float) -> dict:
    from threadpoolctl import threadpool_limits

    from rheolin.data import example_path
    from rheolin.floquet import floquet
    from rheolin.io import read_model
    from rheolin.results import solve_point

    lm = read_model(example_path(name))
    h = lm.spec.harmonics
    with threadpool_limits(1):
        t = time.perf_counter()
        p = solve_point(lm.model, speed, order=h.order, max_order=h.max_order, stability=False)
        solve = time.perf_counter() - t
        t = time.perf_counter()
        res = floquet(p.assembled.system)
        flo = time.perf_counter() - t
    verdict = ("stable" if res.stable else "unstable") + ("" if res.decided else ", undecided")
    return {
        "solve": solve,
        "floquet": flo,
        "n": p.assembled.system.n,
        "harmonics": len(p.solution.harmonics),
        "verdict": verdict,
    }


def _stretch(name: str, grid: np.ndarray) -> float:
    """CPU seconds per point of 32 consecutive speeds of a 1000-speed study (2 blocks)."""
    from rheolin.budget import memory_budget
    from rheolin.data import example_path
    from rheolin.study import StudySpec
    from rheolin.study.worker import ChunkTask, compute_chunk

    spec = StudySpec.create(example_path(name), grid)
    first = (grid.size // 2) // spec.block * spec.block
    t = time.process_time()
    compute_chunk(ChunkTask(spec, 0, list(range(first, first + 32)), memory_budget()))
    return (time.process_time() - t) / 32


def _run(spec) -> dict:
    from rheolin.study import run_study
    from rheolin.study.executor import local_cluster

    folder = Path(tempfile.mkdtemp(prefix="bench-wind-"))
    marks: dict[str, float] = {}

    def progress(event):
        marks.setdefault(event.phase, time.perf_counter())

    t0 = time.perf_counter()
    with local_cluster(2) as client:
        start = time.perf_counter() - t0
        res = run_study(spec, out=folder, client=client, progress=progress)
        rss = sorted(v / 1024 for v in client.run(_maxrss).values())
        cpu = sorted(client.run(_cpu).values())
    wall = time.perf_counter() - t0
    end = marks.get("maps", t0 + wall)
    points = end - marks["points"]
    smap = res.maps.get(0)
    ranges = [
        f"{r.lower / RPM:.2f}..{r.upper / RPM:.2f} rpm ({r.label or r.mechanism})"
        for r in (smap.ranges if smap is not None else [])
    ]
    decided = int(np.sum(np.asarray(smap.decided, bool))) if smap is not None else 0
    stable = int(np.sum(np.asarray(smap.stable, bool))) if smap is not None else 0
    shutil.rmtree(folder, ignore_errors=True)
    return dict(
        wall=wall,
        points=points,
        per_point=2 * points / spec.n_points,
        start=start,
        maps=(t0 + wall - marks["maps"]) if "maps" in marks else 0.0,
        decided=decided,
        stable=stable,
        ranges="; ".join(ranges),
        rss=", ".join(f"{m:.0f}" for m in rss),
        cpu=", ".join(f"{c:.0f}" for c in cpu),
    )


def _maxrss() -> int:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


if __name__ == "__main__":
    main()
