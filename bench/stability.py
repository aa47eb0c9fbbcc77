"""Floquet stability of the embedded gearbox on the harmonic lattice (not a test).

(a) One verdict at 3000 rpm: time and peak memory, against one steady-state solve of the same
    model (closure order 3, 2,945 harmonics, ``stability=False``) measured in the same run.
(b) Lattice order against the accuracy of the largest real part at 3000 rpm: orders 1..3
    computed in full, order 4 and 5 near the leading exponent only.
(c) A stability map over 1500-4500 rpm (``--speeds``, default 50 speeds): seconds per speed,
    peak memory, decided verdicts, unstable ranges and their mechanisms, and two sample
    speeds checked against a lattice two orders finer (near their leading exponents).
(d) A run-up across an unstable range: the gearbox variant of
    ``tests/stability/gear_variants.py`` (72 DOFs, a principal parametric resonance of its
    polymer second mesh at 3439-3877 rpm) every 25 rpm from 3200 to 4100 rpm as a sweep does
    it (each solve from the previous solution, each verdict continued from the previous one):
    CPU seconds of the verdict against the solve per speed, inside / near (within 100 rpm of
    an edge) / far from the range; then the map's bounds from samples every 100 rpm against
    the monodromy reference (``tests/stability/data/gear_variant_ranges.json``).
(e) The Campbell diagram of the embedded gearbox at 0:6000:250 rpm with and without its
    stability map (CPU seconds per speed), and ``rheolin campbell`` with ``--stability off``
    and with its default check, alternated twice (wall and CPU seconds of the faster run of
    each); the map also with each speed's diagram computed beside its verdict.

Every measurement runs in its own subprocess (peak RSS from ``/proc``, see ``_memory.py``).

Usage::

    OPENBLAS_NUM_THREADS=1 python bench/stability.py [--speeds 50]
        [--sections verdict,orders,map,runup,campbell] [--out bench/results/stability.md]

Times in (d) and (e) are CPU seconds of the process (``time.process_time``): the machine the
figures come from was shared, and wall time measured the other processes too.

Design notes
------------
The figures behind the constants and choices of ``rheolin.floquet`` (their comments give the
reason in one sentence and point here). All on the embedded gearbox at 3000 rpm unless said,
BLAS on one thread, 2 cores, timed with ``time.perf_counter`` around the step named inside
one ``rl.floquet(system)`` call (or over the whole verdict); the commit that made the choice
says more (``git show <commit>``).

* ``shift_invert.SPLU``, the ordering of ``Q(sigma)`` (c1e7168): SuperLU in symmetric mode
  (minimum degree on ``A + A^T``, diagonal pivots above 1 % of the column) against column AMD
  with a 0.1 threshold: order 2 (4,410 unknowns) 6.5 ms against 8 ms per factor, order 3
  (14,994) 25 ms against 80-170 ms, with 2-3x less fill and 2x faster solves (1.2 against
  3 ms at order 3); residuals 1e-12 either way. The verdict went from 4.1 to 3.1 s.
* ``shift_invert.PARDISO_ABOVE`` and ``PARDISO_ABOVE_ARNOLDI`` (c1e7168, 11d663b): factor /
  solve times, MKL PARDISO (refining only after perturbed pivots) against SuperLU (symmetric
  mode): order 1 (882 unknowns) 0.33 / 0.085 ms against 0.40 / 0.040 ms; order 2 (4,410)
  1.9-2.7 / 0.4-0.5 ms against 2.4-7 / 0.2-0.25 ms (SuperLU's pivoting varies with the shift:
  4.3 ms on average over a verdict, whose order-2 confirmation took 0.12 s less per speed with
  PARDISO); order 3 (14,994) 10-11.5 / 1.4-2.1 ms against 18-40 / 1.0-1.2 ms; order 4
  (41,454) 74 / 5.5 ms against 550 / 11 ms. A cold Arnoldi run (up to 54 solves per factor)
  favours SuperLU's solves up to order 3. With the ordering reused
  (``shift_invert.Ordered``) a polish's factor and three solves cost 4.5 ms against 7.2 with
  PARDISO at order 2 (4,410 unknowns; PARDISO's solves 1.3 ms against SuperLU's 0.4), about
  the same at order 3, and 20 / 33 ms against 44 / 72 ms on the order-1 lattices of the fine
  gearbox (13,050 and 24,930 unknowns): ``PARDISO_ABOVE`` is 20,000.
* ``shift_invert.Ordered``: SuperLU's minimum-degree ordering of ``Q(sigma)`` depends on its
  pattern only, which every shift of a lattice shares; factorizing the symmetrically
  permuted ``Q[p][:, p]`` in its natural order gives the same fill (1.23 and 1.35 x the
  entries) in 0.55 ms against 1.19 (order 1, 882 unknowns) and 3.3 against 4.6 ms (order 2).
  Over the 24 spinning speeds of the Campbell diagram the exponents are those of a fresh
  ordering to 1e-12.
* ``search.CONFIRM_STEPS``: searches started from a coarser lattice's eigenvectors, at 1000,
  2000, ..., 5000 rpm: 69 such searches, 41 of which ended at the first checkpoint (10 steps);
  with a first checkpoint at 4 steps none ended there; with checkpoints at 6 and 8, 14 end at
  6 steps, 18 at 8 and 9 at 10 (the others later, as before), with the same exponents (to
  1e-12) at all 24 Campbell speeds.
* ``stability_map`` assembles through ``model.speed_template()``: the gearbox's system in
  4.7 ms against 72 ms for ``model.assemble``, the same matrices (bit for bit).
* ``averaged.Averaged.gershgorin`` computes every mode's radius on its first call: 28 ms
  for the gearbox's 252 modes, where the searches and confirmations asked for the upper half
  first (15 ms) and then a few modes at a time (about 12 calls of 4 ms a speed).
* ``shift_invert.pencil_norms`` (c1e7168): assembling the first-order pencil for its 1-norms
  cost 0.15 s at order 3; the column sums of the lattice couplings give the same norms
  (``tests/stability/test_lattice.py`` checks them against ``scipy.sparse.linalg.norm``).
* ``shift_invert.polish`` (c1e7168): reusing the search's factor at ``sigma`` with
  shift-invert steps of the first-order pencil gave the same vectors to 1e-15 but took 5-13
  steps where one LU of ``Q(lambda)`` and three solves do, and the kept factors cost memory.
* ``search.WARM_STEPS`` (0e988ce): a first checkpoint at 4 steps for a search started from
  the previous speed's vectors halves the order-1 Arnoldi time (0.055 -> 0.026 s); a
  coarse-to-fine warm start gained nothing from it.
* ``grown.LEAK_ENERGY``, ``grown.FAR`` (the grown confirmation lattice): over 250-6000 rpm
  every 250 rpm, one process, the two ways alternated twice: 20.3-21.1 CPU s against
  25.9-31.6 with order 2 (the same verdicts and largest real parts at all 24 speeds); the
  grown lattice holds 15-29 harmonics where order 2 holds 35-61. The threshold barely
  matters (7 speeds, first version: 10.2, 10.9 and 10.3 s at 0.02, 0.05 and 0.15 against
  15.7 s), but 0.02 took all five cost-1 steps at 5000 rpm (57 harmonics). ``FAR`` = 10
  left out 250-2000 rpm (clusters linked to the open ones at -322 and -523 1/s against the
  leading -51 1/s); the gear variant's open cluster at 3825 rpm holds the leading exponent.
* ``search.STALL_CHECKPOINT`` (527de51): before it, the 10 cold searches that could not meet
  their quota with centred copies ran to 54 steps: 0.70 of 0.93 s of Arnoldi at order 2; the
  verdict went from 3.05 to 2.7 s with the same exponents.
* ``continuation.TRACK_POLISH`` (eba328d): from one speed to the next of a run-up, the
  averaged shift predicts the exponents to 0.1-4 rad/s; one polish then leaves a backward
  error of 1e-10 to 1e-9 on some.
* ``representatives.Settler`` (28e5e98): a result holding a settler that holds the result (a
  reference cycle) keeps the finer lattices' operators and PARDISO factors alive until a full
  garbage collection: 2 GB per worker over the 1000-speed run-up (``bench/sweep.py --full``).
* ``api.DEFAULT_LATTICE_ORDER`` (f615442): order 1 decides the gearbox in 1.0 s against
  2.4 s at order 2, the same verdict and largest real part to 1e-11 (section (b) of this
  bench).
* ``lattice_run.single_thread_blas`` (96d8b06): the lattice kernels are many small products; with
  two BLAS threads the verdict took twice as long.
* ``averaged.STANDARD_COND`` (9a1373b): the time-averaged modes by ``B^-1 A`` take 0.05 s
  against 0.25 s by QZ (252 x 252).
* ``averaged._from_modal`` (7f3c79b): taking the averaged modes from a modal solve's
  decomposition of the same system costs 8.5 ms instead of 23 ms per verdict.
* ``averaged.Averaged.gershgorin`` (4c163ab): the radii on the couplings' nonzero rows and
  columns only are 4x faster than on the whole modal transform.
* ``checks.Outer.estimate`` (012d1ee): a third of the outer harmonics are exact zeros of one
  of the couplings; only those both couplings reach are summed.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from _memory import reset_peak, status_kb
from _runup import runup, runup_lines, splice

RPM = np.pi / 30


def _model():  # type: ignore[no-untyped-def]
    from rheolin.data import example_path
    from rheolin.io import load_model

    return load_model(example_path("gearbox"))


# --------------------------------------------------------------------------- workers
def _verdict(rpm: float) -> dict:
    import rheolin as rl
    from rheolin.results.compute import solve_point

    model = _model()
    solve_point(model, 3000 * RPM, stability=False)  # warm-up (imports, caches)
    reset_peak()
    t = time.perf_counter()
    p = solve_point(model, rpm * RPM, stability=False)
    solve_s = time.perf_counter() - t
    solve_mb = status_kb("VmHWM") / 1024
    system = model.assemble(rpm * RPM).system
    rl.floquet(model.assemble(2000 * RPM).system)  # warm-up (MKL, caches)
    base_mb = status_kb("VmRSS") / 1024
    reset_peak()
    t = time.perf_counter()
    res = rl.floquet(system)
    seconds = time.perf_counter() - t
    return {
        "solve_seconds": solve_s,
        "solve_peak_mb": solve_mb,
        "harmonics": len(p.harmonics),
        "seconds": seconds,
        "peak_mb": status_kb("VmHWM") / 1024,
        "above_mb": status_kb("VmHWM") / 1024 - base_mb,
        "order": res.lattice.order if res.lattice is not None else None,
        "lattice": len(res.lattice) if res.lattice is not None else None,
        "hill_size": int(res.info.get("hill_size", 0)),
        "estimate_mb": res.info.get("memory_estimate", 0) / 2**20,
        "decided": bool(res.decided),
        "stable": bool(res.stable),
        "max_real": float(res.max_real),
        "leading_hz": float(abs(res.leading.imag) / (2 * np.pi)),
        "computed": int(res.exponents.size),
        "certified": int(2 * len(res.info.get("certified_modes", []))),
        "settled": res.info.get("confirmed"),
    }


def _orders(rpm: float) -> dict:
    import rheolin as rl

    system = _model().assemble(rpm * RPM).system
    rows = []
    lead = None
    for p in (1, 2, 3, 4, 5):
        t = time.perf_counter()
        if p <= 3:
            res = rl.floquet(system, method="lattice", order=p)
            lead = res.exponents[res.exponents.real >= res.max_real - 1e-9]
        else:
            res = rl.floquet(system, method="lattice", order=p, near=lead)
        rows.append(
            {
                "order": p,
                "lattice": len(res.lattice),
                "max_real": float(res.max_real),
                "truncation": float(res.truncation[0]),
                "decided": bool(res.decided) if p <= 3 else None,
                "seconds": time.perf_counter() - t,
                "full": p <= 3,
            }
        )
    return {"rows": rows}


def _map(count: int) -> dict:
    import rheolin as rl
    from rheolin.stability import stability_map

    model = _model()
    speeds = np.linspace(1500, 4500, count) * RPM
    per: list[float] = []
    last = [time.perf_counter()]

    def tick(i: int, res: object) -> None:
        now = time.perf_counter()
        per.append(now - last[0])
        last[0] = now

    reset_peak()
    t = time.perf_counter()
    smap = stability_map(model, speeds, refine=1e-5, progress=tick)
    seconds = time.perf_counter() - t
    checks = []
    for rpm in (1500 + 1000, 4500 - 500):
        system = model.assemble(rpm * RPM).system
        res = rl.floquet(system)
        lead = res.exponents[res.exponents.real >= res.max_real - 1e-9]
        fine = rl.floquet(system, method="lattice", order=res.lattice.order + 2, near=lead)
        checks.append(
            {
                "rpm": rpm,
                "order": res.lattice.order,
                "max_real": float(res.max_real),
                "fine_max_real": float(fine.max_real),
                "diff": float(abs(fine.max_real - res.max_real)),
                "estimate": float(10 * res.truncation[0]),
            }
        )
    return {
        "speeds": count,
        "seconds": seconds,
        "per_speed": per,
        "peak_mb": status_kb("VmHWM") / 1024,
        "decided": int(np.sum(smap.decided)),
        "stable": int(np.sum(smap.stable)),
        "max_real": float(np.max(smap.max_real)),
        "ranges": [
            {"lower_rpm": r.lower / RPM, "upper_rpm": r.upper / RPM, "label": r.label}
            for r in smap.ranges
        ],
        "checks": checks,
        "info": {k: v for k, v in smap.info.items() if k != "seconds"},
    }


def _campbell(step: float) -> dict:
    from rheolin.stability import campbell, stability_map
    from rheolin.study.run import MAP_PRECISION

    model = _model()
    speeds = np.arange(0.0, 6000.0 + step / 2, step) * RPM  # as `rheolin campbell 0:6000:...`
    c = time.process_time()
    campbell(model, speeds)
    alone = time.process_time() - c
    per: list[float] = []
    orders: list[int] = []
    last = [time.process_time()]

    def tick(i: int, res: object) -> None:
        now = time.process_time()
        per.append(now - last[0])
        last[0] = now
        lattice = getattr(res, "lattice", None)
        orders.append(lattice.order if lattice is not None else 0)

    c = time.process_time()
    smap = stability_map(model, speeds, refine=MAP_PRECISION, progress=tick)
    check = time.process_time() - c
    # the same, with the diagram of each speed computed right after its verdict (in the
    # map's progress call, timed apart): the two see the same state of a shared machine,
    # whose speed drifts by 20-30 % over a minute
    beside = [0.0]

    def diagram_too(i: int, res: object) -> None:
        now = time.process_time()
        campbell(model, speeds[i : i + 1])
        beside[0] += time.process_time() - now

    c = time.process_time()
    stability_map(model, speeds, refine=MAP_PRECISION, progress=diagram_too)
    both = time.process_time() - c
    return {
        "speeds": int(speeds.size),
        "campbell": alone,
        "check": check,
        "interleaved": {"campbell": beside[0], "check": both - beside[0]},
        "per_speed": per,
        "orders": orders,
        "continued": int(smap.info.get("continued", 0)),
        "decided": int(np.sum(smap.decided)),
        "stable": int(np.sum(smap.stable)),
        "ranges": len(smap.ranges),
        "cli": _campbell_cli(step),
    }


def _campbell_cli(step: float) -> dict:
    """``rheolin campbell gearbox.toml --speeds 0:6000:<step>rpm`` without its stability
    check, with it (default: on worker processes) and with it in one process, alternated
    twice: wall and CPU seconds (workers included) of the faster run of each."""
    import os
    import resource
    import tempfile

    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        rheolin = [sys.executable, "-m", "rheolin.cli"]
        # as a user runs it: no thread variables (the command limits BLAS where it helps)
        env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")}
        model = subprocess.run(
            [*rheolin, "example", "gearbox"], check=True, env=env, capture_output=True, text=True
        )
        Path(tmp, "gearbox.toml").write_text(model.stdout)
        # alternated twice, the faster of each kept: the machine's speed drifts. "auto": the
        # default (the check on a worker per core while the diagram is drawn), "one": the
        # check in the command's process after the diagram (--workers 1)
        options = {"off": ["--stability", "off"], "auto": [], "one": ["--workers", "1"]}
        for flag in ("off", "auto", "one", "off", "auto", "one"):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            t = time.perf_counter()
            done = subprocess.run(
                [*rheolin, "campbell", "gearbox.toml", "--speeds", f"0:6000:{step:g}rpm",
                 *options[flag], "--out", f"out_{flag}"],
                cwd=tmp, env=env, capture_output=True, text=True,
            )  # fmt: skip
            wall = time.perf_counter() - t
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
            if flag not in out or cpu < out[flag]["cpu"]:
                out[flag] = {"wall": wall, "cpu": cpu, "exit": done.returncode}
    return out


def _run(args: list[str]) -> dict:
    out = subprocess.run(
        [sys.executable, __file__, *args], capture_output=True, text=True, check=True
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


# --------------------------------------------------------------------------- report
def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--speeds", type=int, default=50)
    ap.add_argument("--sections", default="verdict,orders,map,runup,campbell")
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--worker", nargs="*", default=None, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.worker:
        kind, value = a.worker[0], a.worker[1]
        workers = {
            "verdict": _verdict,
            "orders": _orders,
            "map": _map,
            "runup": runup,
            "campbell": _campbell,
        }
        arg = int(value) if kind == "map" else float(value)
        print(json.dumps(workers[kind](arg)))
        return
    sections = a.sections.split(",")
    alone = {
        "runup": lambda: runup_lines(_run(["--worker", "runup", "25"])),
        "campbell": lambda: _campbell_lines(_run(["--worker", "campbell", "250"])),
    }
    if len(sections) == 1 and sections[0] in alone and a.out and a.out.exists():
        # one section into an existing file: the other sections keep their figures
        text = splice(a.out.read_text(), alone[sections[0]]())
        print(text)
        tmp = a.out.with_suffix(".tmp")
        tmp.write_text(text)
        tmp.replace(a.out)
        return
    lines = [
        "# Floquet stability of the embedded gearbox (bench/stability.py)",
        "",
        "2 cores, BLAS on one thread, each measurement in its own process.",
        "",
    ]
    if "verdict" in sections and "orders" in sections:
        lines += _first(_run(["--worker", "verdict", "3000"]), _run(["--worker", "orders", "3000"]))
    if "map" in sections:
        lines += _map_lines(_run(["--worker", "map", str(a.speeds)]))
    if "runup" in sections:
        lines += runup_lines(_run(["--worker", "runup", "25"]))
    if "campbell" in sections:
        lines += _campbell_lines(_run(["--worker", "campbell", "250"]))
    text = "\n".join(lines) + "\n"
    print(text)
    if a.out:
        a.out.parent.mkdir(parents=True, exist_ok=True)
        a.out.write_text(text)


def _first(v: dict, o: dict) -> list[str]:
    lines = [
        "## One verdict at 3000 rpm",
        "",
        "| | value |",
        "|---|---|",
        f"| steady-state solve (closure order 3, {v['harmonics']} harmonics) | "
        f"{v['solve_seconds']:.2f} s, peak {v['solve_peak_mb']:.0f} MB |",
        f"| stability verdict | {v['seconds']:.2f} s, peak {v['peak_mb']:.0f} MB: "
        f"{v['above_mb']:.0f} MB above the process before it (estimate "
        f"{v['estimate_mb']:.0f} MB) |",
        f"| verdict / solve | **{v['seconds'] / v['solve_seconds']:.1f}x** |",
        f"| lattice | order {v['order']}, {v['lattice']} harmonics, Hill size {v['hill_size']} |",
        f"| verdict | {'stable' if v['stable'] else 'UNSTABLE'}, "
        f"{'decided' if v['decided'] else 'undecided'}; largest real part "
        f"{v['max_real']:.6g} 1/s at {v['leading_hz']:.1f} Hz |",
        f"| exponents | {v['computed']} computed, {v['certified']} certified by Gershgorin "
        f"discs; unresolved settled: {v['settled']} |",
        "",
        "## Lattice order against the largest real part (3000 rpm)",
        "",
        "| order | harmonics | largest real part [1/s] | change | truncation estimate | "
        "decided | seconds |",
        "|---|---|---|---|---|---|---|",
    ]
    prev = None
    for r in o["rows"]:
        change = "" if prev is None else f"{abs(r['max_real'] - prev):.2e}"
        how = "" if r["full"] else " (near the leading exponent only)"
        dec = "" if r["decided"] is None else ("yes" if r["decided"] else "no")
        lines.append(
            f"| {r['order']}{how} | {r['lattice']} | {r['max_real']:.10g} | {change} | "
            f"{r['truncation']:.2e} | {dec} | {r['seconds']:.1f} |"
        )
        prev = r["max_real"]
    return lines


def _map_lines(m: dict) -> list[str]:
    per = np.array(m["per_speed"])
    lines = [
        "",
        f"## Stability map, {m['speeds']} speeds over 1500-4500 rpm",
        "",
        f"- {m['seconds']:.0f} s in all ({np.median(per):.1f} s median per speed, "
        f"{per.min():.1f}-{per.max():.1f} s), peak {m['peak_mb']:.0f} MB;",
        f"- {m['decided']} of {m['speeds']} verdicts decided, {m['stable']} stable; "
        f"largest real part {m['max_real']:.5g} 1/s;",
        "- unstable ranges: "
        + (
            "; ".join(
                f"{r['lower_rpm']:.1f}-{r['upper_rpm']:.1f} rpm ({r['label']})" for r in m["ranges"]
            )
            or "none"
        ),
        "",
        "| rpm | order | largest real part | order + 2 (near it) | difference | 10 x estimate |",
        "|---|---|---|---|---|---|",
    ]
    for c in m["checks"]:
        lines.append(
            f"| {c['rpm']:.0f} | {c['order']} | {c['max_real']:.10g} | {c['fine_max_real']:.10g}"
            f" | {c['diff']:.2e} | {c['estimate']:.2e} |"
        )
    return lines


def _campbell_lines(c: dict) -> list[str]:
    per = np.array(c["per_speed"])
    cli = c["cli"]
    off, on, one = cli["off"], cli["auto"], cli["one"]
    il = c["interleaved"]
    worst = int(np.argmax(per))
    step = 6000.0 / (c["speeds"] - 1)
    lines = [
        "",
        f"## Campbell diagram with its stability check ({c['speeds']} speeds, 0:6000:{step:g} rpm)",
        "",
        "`python bench/stability.py --sections campbell` (CPU seconds in one process; the",
        "command lines alternated twice, wall and CPU of the faster run of each):",
        "",
        "| | CPU s | wall s |",
        "|---|---|---|",
        f"| `campbell()` alone | {c['campbell']:.1f} | |",
        f"| `stability_map()` over the same speeds | {c['check']:.1f} | |",
        f"| check / diagram | {c['check'] / c['campbell']:.2f}x | |",
        f"| interleaved speed by speed: `stability_map()` / `campbell()` | "
        f"{il['check']:.1f} / {il['campbell']:.1f} | |",
        f"| check / diagram, interleaved | **{il['check'] / il['campbell']:.2f}x** | |",
        f"| `rheolin campbell gearbox.toml --speeds 0:6000:{step:g}rpm --stability off` | "
        f"{off['cpu']:.1f} | {off['wall']:.1f} |",
        f"| the same with its default stability check (a worker per core, the diagram "
        f"drawn meanwhile) | {on['cpu']:.1f} | {on['wall']:.1f} |",
        f"| on / off | **{on['cpu'] / off['cpu']:.2f}x** | **{on['wall'] / off['wall']:.2f}x** |",
        f"| the check in the command's process (`--workers 1`) | {one['cpu']:.1f} | "
        f"{one['wall']:.1f} |",
        f"| `--workers 1` / off | {one['cpu'] / off['cpu']:.2f}x | "
        f"{one['wall'] / off['wall']:.2f}x |",
        "",
        f"Per speed of the map: median {np.median(per):.2f} s, the slowest "
        f"{per[worst]:.2f} s at {worst * step:g} rpm, the standstill {per[0]:.2f} s (the frozen "
        f"system); lattice orders {sorted(set(c['orders'][1:]))}; {c['continued']} speeds "
        f"continued from the previous one; {c['decided']} of {c['speeds']} verdicts decided "
        f"({c['stable']} stable), {c['ranges']} unstable ranges; exit codes "
        f"{off['exit']} / {on['exit']} / {one['exit']}.",
    ]
    return lines


if __name__ == "__main__":
    main()
