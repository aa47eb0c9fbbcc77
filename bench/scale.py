"""Scale: the embedded gearbox in a flexible housing of ~1e5 FE DOF (not a test).

The housing of ``rheolin example gearbox-housing`` (:mod:`rheolin.fe.gearbox_housing`: a
closed steel box of hexahedra, six averaged bearing seats, clamped feet) at a fine mesh.
Steps, timed side by side in one process, with the peak resident memory:

1. mesh and FE matrices;
2. Craig-Bampton condensation (``rheolin.fe.condense``: every fixed-interface mode below
   ``--cutoff``), saved as the ``.npz`` a model file takes;
3. the gearbox model file with its six bearings rewired from ground to the housing
   (``other_body``), read back;
4. one steady state (``method="auto"``, the gearbox's harmonic set), and its Floquet
   verdict when asked (``--stability``);
5. with ``--runup``: the stability map over those speeds (each continued from the previous
   one where the map does that; on ``--workers`` processes), the verdict per speed (and its
   CPU seconds in one process) and the map's time.

``--shaft-dof N`` meshes the gearbox's shafts finely first (every element split so that the
shafts have about N DOF, :func:`rheolin.data.fine.refine_model`), the housing unchanged;
``--band-check K`` adds the verdict from a band of K modes beside the default one (below the
dense limit: the band against the dense method on the same model).

Usage::

    OPENBLAS_NUM_THREADS=1 python bench/scale.py --element 0.006 --out bench/results/scale.md
    OPENBLAS_NUM_THREADS=1 python bench/scale.py --element 0.006 --shaft-dof 2600 \
        --runup 2700 2800 2900 3000 3100 3200 3300 --workers 2 --out bench/results/scale_fine.md
    OPENBLAS_NUM_THREADS=1 python bench/scale.py --element 0.006 --shaft-dof 1800 --stability \
        --band-check 320 --out bench/results/scale_dense.md
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np
import tomli_w

sys.path.insert(0, str(Path(__file__).parent))
import rheolin as rl
from _memory import reset_peak, status_kb
from rheolin.data.fine import gearbox_subdivisions, refine_model
from rheolin.fe import condense
from rheolin.fe.gearbox_housing import ORIGIN, housing, rewired, seat_couplings
from rheolin.io import read_model
from rheolin.results.compute import solve_point


def peak_mb() -> float:
    return status_kb("VmHWM") / 1024


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--element", type=float, default=0.006, help="element size [m]")
    ap.add_argument("--cutoff", type=float, default=3000.0, help="modes kept below [Hz]")
    ap.add_argument("--speed", type=float, default=3000.0, help="input speed [rpm]")
    ap.add_argument("--stability", action="store_true", help="also the Floquet verdict")
    ap.add_argument("--shaft-dof", type=int, default=0, help="mesh the shafts to ~N DOF")
    ap.add_argument("--runup", type=float, nargs="*", default=[], help="map speeds [rpm]")
    ap.add_argument("--workers", type=int, default=1, help="worker processes of the run-up")
    ap.add_argument(
        "--band-check",
        type=int,
        default=0,
        help="with --stability: also the verdict from a band of N modes (below the dense limit)",
    )
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    rows: list[tuple[str, str]] = []
    t_all = time.perf_counter()

    t0 = time.perf_counter()
    fe = housing(args.element)
    rows.append(("mesh and FE matrices", f"{fe.n_dof:,} DOF, {time.perf_counter() - t0:.1f} s"))
    print(rows[-1], f"peak {peak_mb():.0f} MB", flush=True)

    t0 = time.perf_counter()
    feet = fe.dofs_of(fe.nodes_where(lambda x: x[:, 1] < ORIGIN[1] + 1e-9))
    body = condense(fe, None, seat_couplings(fe, args.element), modes=10, fixed=feet,
                    cutoff_hz=args.cutoff)  # fmt: skip
    t_cb = time.perf_counter() - t0
    f = np.asarray(body.frequencies)
    rows.append((
        "Craig-Bampton condensation",
        f"{t_cb:.1f} s: 6 seats x 6 + {body.n_modes} modes ({f.min():.0f}-{f.max():.0f} Hz), "
        f"peak {peak_mb():.0f} MB so far",
    ))  # fmt: skip
    print(rows[-1], flush=True)
    peak_before = peak_mb()  # the solve's measurement below resets the high-water mark

    with tempfile.TemporaryDirectory() as tmp:
        npz = Path(tmp) / "housing.npz"
        body.save(npz)
        model_path = Path(tmp) / "gearbox_in_housing.toml"
        text = rewired(npz.name, body.positions)
        if args.shaft_dof:
            spec = tomllib.loads(text)
            m = gearbox_subdivisions(args.shaft_dof)
            text = tomli_w.dumps(refine_model(spec, {s["name"]: m for s in spec["shafts"]}))
        model_path.write_text(text)
        t0 = time.perf_counter()
        lm = read_model(model_path)
        model = lm.model
        W = args.speed * np.pi / 30
        h = lm.spec.harmonics
        base = status_kb("VmRSS")
        reset_peak()
        p = solve_point(model, W, order=h.order, max_order=h.max_order, stability=False)
        solve_peak = (status_kb("VmHWM") - base) * 1024
        t_solve = time.perf_counter() - t0
        sol = p.solution
        estimate = float(sol.info.get("memory_estimate", float("nan")))
        rows.append((
            "steady state (read, assemble, solve)",
            f"{t_solve:.1f} s: {p.assembled.system.n} DOF x {len(p.harmonics):,} harmonics, "
            f"{sol.method} ({sol.info.get('strategy', '-')}), {sol.iterations} iterations, "
            f"backward error {sol.residual:.1e}, success {sol.success}; memory: estimate "
            f"{estimate / 1e6:.0f} MB, measured {solve_peak / 1e6:.0f} MB above the process",
        ))  # fmt: skip
        print(rows[-1], flush=True)
        if args.stability:
            checks: list[tuple[str, int | None]] = [("Floquet verdict", None)]
            if args.band_check:
                checks.append((f"Floquet verdict from a band of {args.band_check} modes",
                               args.band_check))  # fmt: skip
            for label, band_modes in checks:
                t0 = time.perf_counter()
                res = rl.floquet(p.assembled.system, band=band_modes)
                band = res.info.get("band", {})
                how = f"{res.method} method"
                if band:  # the band method: its size and bound
                    how += (
                        f", band of {band.get('modes')} modes, kappa_C "
                        f"{band.get('kappa', float('nan')):.3g} ({band.get('norm', '-')} norm)"
                    )
                rows.append((
                    label,
                    f"{time.perf_counter() - t0:.1f} s: {'stable' if res.stable else 'unstable'}, "
                    f"decided {res.decided}, largest real part {res.max_real:.10g} 1/s "
                    f"(+-{res.max_real_uncertainty:.2g}), {how}",
                ))  # fmt: skip
                print(rows[-1], flush=True)
        if args.runup:
            rows.append(_runup(model, args.runup, args.workers))
            print(rows[-1], flush=True)
    total = time.perf_counter() - t_all
    peak = max(peak_before, peak_mb())
    asked = os.environ.get("RHEOLIN_MEMORY_BUDGET")  # a budget set for the run
    budget = f"RHEOLIN_MEMORY_BUDGET={asked} " if asked else ""
    rows.append(("total", f"{total:.0f} s, peak resident memory {peak:.0f} MB"))
    text = (
        f"# Gearbox in a {fe.n_dof:,}-DOF housing\n\n"
        f"`{budget}OPENBLAS_NUM_THREADS=1 python bench/scale.py --element {args.element} --cutoff "
        f"{args.cutoff:g} --speed {args.speed:g}{' --stability' if args.stability else ''}"
        f"{f' --shaft-dof {args.shaft_dof}' if args.shaft_dof else ''}"
        f"{' --runup ' + ' '.join(f'{x:g}' for x in args.runup) if args.runup else ''}"
        f"{f' --workers {args.workers}' if args.workers > 1 else ''}"
        f"{f' --band-check {args.band_check}' if args.band_check else ''}`, "
        "2 cores.\n\n| step | result |\n|---|---|\n" + "".join(f"| {a} | {b} |\n" for a, b in rows)
    )
    print(text)
    if args.out:
        Path(args.out).write_text(text)
        print(f"wrote {args.out}")


def _runup(model: object, rpm: list[float], workers: int = 1) -> tuple[str, str]:
    """The stability map over ``rpm`` (on ``workers`` processes): per speed its verdict (and
    its CPU seconds when in this process), the map's wall time and the workers' peak memory."""
    from rheolin.stability import stability_map
    from rheolin.study.run import MAP_PRECISION

    speeds = np.asarray(sorted(rpm)) * np.pi / 30
    lines: dict[int, str] = {}
    last = [time.process_time()]

    def tick(i: int, res: object) -> None:
        now = time.process_time()
        band = getattr(res, "info", {}).get("band", {})
        state = "undecided" if not res.decided else ("stable" if res.stable else "unstable")
        cost = f"{now - last[0]:.0f} CPU s, " if workers == 1 else ""
        lines[i] = (
            f"{speeds[i] * 30 / np.pi:g} rpm: {state}, {res.max_real:.6g} 1/s, "
            f"{cost}band {band.get('modes', '-')} modes "
            f"(kappa_C {band.get('kappa', float('nan')):.2f}, {band.get('norm', '-')} norm)"
        )
        print(lines[i], flush=True)
        last[0] = now

    t0, wall = time.process_time(), time.perf_counter()
    peaks = ""
    if workers > 1:
        from rheolin.study.executor import local_cluster

        def worker_peak() -> float:  # MB, the worker process's high-water mark
            with open("/proc/self/status") as f:
                row = next(x for x in f if x.startswith("VmHWM:"))
            return int(row.split()[1]) / 1024

        with local_cluster(workers) as client:
            smap = stability_map(model, speeds, refine=MAP_PRECISION, progress=tick, client=client)
            mb = sorted(client.run(worker_peak).values())
        peaks = ", worker peaks " + " / ".join(f"{x:.0f}" for x in mb) + " MB"
    else:
        smap = stability_map(model, speeds, refine=MAP_PRECISION, progress=tick)
    cpu, wall = time.process_time() - t0, time.perf_counter() - wall
    decided = int(np.sum(smap.decided))
    where = f"{cpu:.0f} CPU s" if workers == 1 else f"{workers} workers, {wall:.0f} s wall{peaks}"
    return (
        f"run-up, {speeds.size} speeds",
        f"{where}, {decided} of {speeds.size} decided, "
        f"{int(smap.info.get('continued', 0))} continued from the previous speed, "
        f"{len(smap.ranges)} unstable ranges: " + "; ".join(lines[i] for i in sorted(lines)),
    )


if __name__ == "__main__":
    main()
