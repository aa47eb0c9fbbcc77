"""Study benchmark: the embedded gearbox over speed, response plus Floquet stability verdicts,
serial and on a local Dask cluster, checkpointed; one run, ratios side by side (not a test).

What it measures (2 cores unless the machine has more):

1. one point at 3000 rpm, serial, one BLAS thread: the steady-state solve, the Floquet
   verdict, and the whole task (:func:`rheolin.study.worker.compute_chunk`: model, solve,
   Floquet, reduction, pickling): what dominates;
2. a run-up over ``--points`` speeds, every ``1000 / points``-th speed of the 1000-speed
   grid 500..6000 rpm, with 1 worker (this process, no Dask) and with 2 worker processes
   (``LocalCluster``): wall times, the speed-up, the time of the stability-map phase, the
   peak memory of each worker (``ru_maxrss``); the full 1000-speed run-up is extrapolated
   from the 2-worker rate (marked "est.": one gearbox speed costs seconds, 1000 of them more
   than this benchmark should take);
3. resume: the same study again (every point in the checkpoint), and after an interruption
   at half the points;
4. Dask's overhead per task (no-op tasks through the same executor as the study) and the
   client's cost of writing one chunk file;
5. the chunk store: one NetCDF file per chunk (what rheolin uses) against one Zarr store
   (region writes plus a done-marker per chunk), on gearbox-sized chunks; reading them all
   back is what :class:`rheolin.study.store.CheckpointStore` saves by keeping the chunks a run
   wrote to assemble its ``sweep.nc``.

Usage::

    python bench/sweep.py [--points 16] [--full] [--out bench/results/sweep.md]

``--full`` also runs the whole 1000-speed run-up on 2 workers (section 2b, minutes).
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
    ap.add_argument("--points", type=int, default=16, help="speeds of the measured subset")
    ap.add_argument("--out", type=Path, default=None, help="write the results (markdown)")
    ap.add_argument(
        "--full", action="store_true", help="also run the whole 1000-speed run-up (2 workers)"
    )
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
    full = np.linspace(500.0, 6000.0, 1000) * RPM
    subset = full[:: max(1, full.size // args.points)][: args.points]
    spec = StudySpec.create(example_path("gearbox"), subset)
    say("# Study benchmark: embedded gearbox, response + Floquet verdicts (bench/sweep.py)")
    say()
    say(
        f"{os.cpu_count()} cores; load average {load0[0]:.2f} at the start (other work on the "
        "machine slows every number below alike)"
    )
    say()
    point = _one_point(spec)
    say("## 1. One point (3000 rpm, serial, one BLAS thread)")
    say()
    say("| part | seconds | share of the task |")
    say("|---|---|---|")
    for name in ("solve", "floquet", "task"):
        say(f"| {name} | {point[name]:.2f} | {point[name] / point['task']:.0%} |")
    say()
    runs = _run_up(spec)
    say(
        f"## 2. Run-up over {subset.size} speeds (every {full.size // subset.size}th of "
        "500..6000 rpm in 1000 steps)"
    )
    say()
    say(
        "| workers | wall [s] | points phase [s] | per point [s] | maps phase [s] | "
        "cluster start [s] | peak RSS per worker [MB] |"
    )
    say("|---|---|---|---|---|---|---|")
    for r in runs:
        say(
            f"| {r['workers']} | {r['wall']:.1f} | {r['points']:.1f} | "
            f"{r['points'] / subset.size:.2f} | {r['maps']:.1f} | {r['start']:.1f} | "
            f"{', '.join(f'{m:.0f}' for m in r['rss'])} |"
        )
    one, two = runs
    say()
    say(
        f"speed-up 1 -> 2 workers: {one['wall'] / two['wall']:.2f}x wall, "
        f"{one['points'] / two['points']:.2f}x on the points; the results are equal "
        f"({two['equal']})"
    )
    ranges = two["ranges"]
    say(f"unstable ranges found: {ranges or 'none'}")
    rate = two["points"] / subset.size
    est = full.size * rate + two["start"] + two["maps"]
    say(
        f"1000-speed run-up on 2 workers, est.: {est:.0f} s = {est / 60:.0f} min "
        f"({full.size} x {rate:.2f} s per point + start + maps phase of the subset)"
    )
    say()
    if args.full:
        whole = _whole(StudySpec.create(example_path("gearbox"), full))
        say("## 2b. The whole run-up: 1000 speeds, 500..6000 rpm, 2 workers")
        say()
        say("| | value |")
        say("|---|---|")
        say(f"| wall, cluster start to results on disk | **{whole['wall']:.0f} s** |")
        say(
            f"| points phase | {whole['points']:.0f} s ({whole['per_point']:.2f} s per point "
            "per worker) |"
        )
        say(f"| maps phase (refining unstable ranges) | {whole['maps']:.1f} s |")
        say(f"| continuation blocks | {whole['block']} speeds |")
        say(f"| verdicts | {whole['decided']} of 1000 decided, {whole['stable']} stable |")
        say(f"| unstable ranges | {whole['ranges'] or 'none'} |")
        say(f"| peak RSS per worker | {whole['rss']} MB |")
        say()
    res = _resume(spec, two["points"])
    say("## 3. Resume")
    say()
    say("| run | wall [s] | points computed |")
    say("|---|---|---|")
    say(f"| whole study, 2 workers | {two['wall']:.1f} | {subset.size} |")
    say(f"| again, everything in the checkpoint | {res['again']:.1f} | 0 |")
    say(f"| after an interruption at half the points | {res['half']:.1f} | {res['missing']} |")
    say()
    say(
        f"a finished study re-assembled: {two['wall'] / res['again']:.0f}x faster than "
        f"computing it; the half-done one: {two['wall'] / res['half']:.1f}x"
    )
    say()
    over = _overhead()
    say("## 4. Overheads")
    say()
    say(
        f"- Dask per task (no-op tasks through the study's executor, 2 workers): "
        f"{over['dask_ms']:.2f} ms; serially: {over['serial_ms']:.3f} ms"
    )
    say(
        f"- writing one gearbox chunk file (1 point) on the client: {over['write_ms']:.1f} ms "
        f"= {over['write_ms'] / 1e3 / point['task']:.2%} of one point's task"
    )
    say()
    store = _stores()
    say("## 5. Chunk store: per-chunk NetCDF against Zarr (gearbox-sized chunks of 4 points)")
    say()
    say("| store | write per chunk [ms] | read all [ms] | files per chunk | commit |")
    say("|---|---|---|---|---|")
    for name, s in store.items():
        say(f"| {name} | {s['write']:.1f} | {s['read']:.0f} | {s['files']:.1f} | {s['commit']} |")
    say()
    load1 = os.getloadavg()
    say(f"load average {load1[0]:.2f} at the end")
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text("\n".join(lines) + "\n")


def _one_point(spec) -> dict[str, float]:
    from threadpoolctl import threadpool_limits

    from rheolin.floquet import floquet
    from rheolin.results import solve_point
    from rheolin.study.worker import ChunkTask, compute_chunk

    lm = spec.loaded(0)
    h = lm.spec.harmonics
    w = 3000 * RPM
    with threadpool_limits(1):
        t = time.perf_counter()
        p = solve_point(lm.model, w, order=h.order, max_order=h.max_order, stability=False)
        solve = time.perf_counter() - t
        t = time.perf_counter()
        floquet(p.assembled.system)
        flo = time.perf_counter() - t
    from rheolin.budget import memory_budget
    from rheolin.study import StudySpec

    one = StudySpec.create(spec.source, [w])
    t = time.perf_counter()
    compute_chunk(ChunkTask(one, 0, [0], memory_budget()))
    task = time.perf_counter() - t
    return {"solve": solve, "floquet": flo, "task": task}


def _run_up(spec) -> list[dict]:
    from rheolin.study import run_study
    from rheolin.study.executor import local_cluster

    out = []
    results = []
    for workers in (1, 2):
        folder = Path(tempfile.mkdtemp(prefix="bench-sweep-"))
        marks: dict[str, float] = {}

        def progress(event, marks=marks):
            marks.setdefault(event.phase, time.perf_counter())

        t0 = time.perf_counter()
        rss: list[float] = []
        if workers == 1:
            start = 0.0
            res = run_study(spec, out=folder, progress=progress)
            rss = [resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024]
        else:
            with local_cluster(workers) as client:
                start = time.perf_counter() - t0
                res = run_study(spec, out=folder, client=client, progress=progress)
                rss = sorted(v / 1024 for v in client.run(_maxrss).values())
        wall = time.perf_counter() - t0
        end_points = marks.get("maps", time.perf_counter())
        points = end_points - marks["points"]
        maps = (time.perf_counter() - marks["maps"]) if "maps" in marks else 0.0
        results.append(res)
        ranges = [
            f"{r.lower / RPM:.1f}..{r.upper / RPM:.1f} rpm ({r.label or r.mechanism})"
            for smap in res.maps.values()
            for r in smap.ranges
        ]
        out.append(
            dict(
                workers=workers,
                wall=wall,
                points=points,
                maps=maps,
                start=start,
                rss=rss,
                ranges="; ".join(ranges),
                folder=folder,
            )
        )
    a, b = (r.dataset.drop_vars("seconds") for r in results)
    out[1]["equal"] = "identical" if a.identical(b) else "NOT identical"
    shutil.rmtree(out[0]["folder"], ignore_errors=True)
    _KEEP["folder"] = out[1]["folder"]
    return out


_KEEP: dict[str, Path] = {}


def _whole(spec) -> dict:
    """The full run-up on a fresh 2-worker cluster, written to a temporary directory."""
    from rheolin.study import run_study
    from rheolin.study.executor import local_cluster

    folder = Path(tempfile.mkdtemp(prefix="bench-sweep-full-"))
    marks: dict[str, float] = {}

    def progress(event):
        marks.setdefault(event.phase, time.perf_counter())

    t0 = time.perf_counter()
    with local_cluster(2) as client:
        res = run_study(spec, out=folder, client=client, progress=progress)
        rss = sorted(v / 1024 for v in client.run(_maxrss).values())
    wall = time.perf_counter() - t0
    end = marks.get("maps", t0 + wall)
    points = end - marks["points"]
    ds = res.dataset
    smap = res.maps.get(0)
    ranges = [
        f"{r.lower / RPM:.1f}..{r.upper / RPM:.1f} rpm ({r.label or r.mechanism})"
        for r in (smap.ranges if smap is not None else [])
    ]
    decided = int(np.sum(np.asarray(smap.decided, bool))) if smap is not None else 0
    stable = int(np.sum(np.asarray(smap.stable, bool))) if smap is not None else 0
    shutil.rmtree(folder, ignore_errors=True)
    return dict(
        wall=wall,
        points=points,
        per_point=2 * points / ds["success"].size,
        maps=(t0 + wall - marks["maps"]) if "maps" in marks else 0.0,
        block=spec.block,
        decided=decided,
        stable=stable,
        ranges="; ".join(ranges),
        rss=", ".join(f"{m:.0f}" for m in rss),
    )


def _maxrss() -> int:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def _resume(spec, points_seconds: float) -> dict:
    from rheolin.study import StudyInterrupted, run_study
    from rheolin.study.executor import local_cluster

    folder = _KEEP["folder"]
    t = time.perf_counter()
    run_study(spec, out=folder, workers=2)
    again = time.perf_counter() - t
    shutil.rmtree(folder, ignore_errors=True)
    half = spec.n_points // 2

    def stop(event):
        if event.done >= half:
            raise KeyboardInterrupt

    with local_cluster(2) as client:
        try:
            run_study(spec, out=folder, client=client, progress=stop)
        except StudyInterrupted:
            pass
    t = time.perf_counter()
    res = run_study(spec, out=folder, workers=2)
    took = time.perf_counter() - t
    shutil.rmtree(folder, ignore_errors=True)
    return {"again": again, "half": took, "missing": res.computed}


def _noop(x: int) -> int:
    return x


def _overhead() -> dict[str, float]:
    from rheolin.data import example_path
    from rheolin.study import StudySpec
    from rheolin.study.executor import DaskExecutor, SerialExecutor, local_cluster
    from rheolin.study.store import CheckpointStore
    from rheolin.study.worker import ChunkTask, compute_chunk

    out = {}
    n = 400
    for name, make in (("serial_ms", None), ("dask_ms", 2)):
        with local_cluster(make) if make else _nothing() as client:
            ex = DaskExecutor(client) if client is not None else SerialExecutor()
            t = time.perf_counter()
            running = 0
            submitted = 0
            while submitted < n or running:
                while submitted < n and running < ex.slots:
                    ex.submit(_noop, submitted)
                    submitted += 1
                    running += 1
                ex.next_done()
                running -= 1
            out[name] = (time.perf_counter() - t) / n * 1e3
    spec = StudySpec.create(example_path("gearbox"), [3000 * RPM])
    from rheolin.budget import memory_budget

    chunk = compute_chunk(ChunkTask(spec, 0, [0], memory_budget())).dataset
    folder = Path(tempfile.mkdtemp(prefix="bench-store-"))
    store = CheckpointStore(folder)
    store.open(spec, budget=memory_budget())
    times = []
    for i in range(10):
        ds = chunk.assign_coords(point=[i])
        t = time.perf_counter()
        store.write(ds)
        times.append(time.perf_counter() - t)
    store.close()
    shutil.rmtree(folder, ignore_errors=True)
    out["write_ms"] = float(np.median(times)) * 1e3
    return out


class _nothing:
    def __enter__(self):
        return None

    def __exit__(self, *exc):
        return False


def _stores() -> dict[str, dict]:
    """Gearbox-sized chunks (1473 harmonics x 21 nodes, 10 bearings, 2 meshes, 4 points)."""
    import xarray as xr

    from rheolin.study.chunks import read_chunk, write_chunk

    rng = np.random.default_rng(0)
    k, n_chunks, nh = 4, 20, 1473

    def chunk(c: int) -> xr.Dataset:
        pts = np.arange(c * k, (c + 1) * k)
        return xr.Dataset(
            {
                "response": (("point", "harmonic", "node"), rng.random((k, nh, 21))),
                "bearing_force": (("point", "bearing", "harmonic"), rng.random((k, 10, nh))),
                "dte": (("point", "mesh", "harmonic"), rng.random((k, 2, nh))),
                "success": (("point",), np.ones(k, dtype=np.int64)),
                "floquet_pickle": (("byte",), rng.integers(0, 255, 30000 * k, dtype=np.uint8)),
            },
            coords={"point": pts},
        )

    out = {}
    folder = Path(tempfile.mkdtemp(prefix="bench-nc-"))
    t = time.perf_counter()
    for c in range(n_chunks):
        write_chunk(chunk(c), folder / f"chunk-{c:07d}.nc")
    write = (time.perf_counter() - t) / n_chunks
    t = time.perf_counter()
    for c in range(n_chunks):
        read_chunk(folder / f"chunk-{c:07d}.nc")
    out["NetCDF per chunk (rheolin)"] = dict(
        write=write * 1e3,
        read=(time.perf_counter() - t) * 1e3,
        files=1.0,
        commit="one rename (temporary file, fsync)",
    )
    shutil.rmtree(folder, ignore_errors=True)
    try:
        import zarr  # noqa: F401
    except ImportError:
        out["Zarr (not installed: pip install zarr)"] = dict(
            write=float("nan"), read=float("nan"), files=float("nan"), commit="-"
        )
        return out
    folder = Path(tempfile.mkdtemp(prefix="bench-zarr-")) / "store.zarr"
    template = xr.concat([chunk(c) for c in range(n_chunks)], dim="point").drop_vars(
        "floquet_pickle"
    )
    enc = {v: {"chunks": (k, *template[v].shape[1:])} for v in template.data_vars}
    template.to_zarr(folder, compute=False, encoding=enc)
    t = time.perf_counter()
    for c in range(n_chunks):
        ds = chunk(c)
        region = {"point": slice(c * k, (c + 1) * k)}
        ds.drop_vars(["floquet_pickle", "point"]).to_zarr(folder, region=region)
        (folder / f"done-{c}").write_bytes(ds["floquet_pickle"].values.tobytes())
    write = (time.perf_counter() - t) / n_chunks
    t = time.perf_counter()
    xr.open_zarr(folder).load()
    read = time.perf_counter() - t
    files = sum(len(f) for _, _, f in os.walk(folder))
    out["Zarr store (region write + marker)"] = dict(
        write=write * 1e3,
        read=read * 1e3,
        files=files / n_chunks,
        commit="several files, then a marker; shapes fixed before the first point",
    )
    shutil.rmtree(folder.parent, ignore_errors=True)
    return out


if __name__ == "__main__":
    main()
