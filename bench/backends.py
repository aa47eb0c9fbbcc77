"""Sparse direct backends side by side: factorization time, peak memory and accuracy.

One complex block ``A = K - w^2 M + i w D`` (``D = 1e-5 K``, ``w = 2 pi 800 Hz``, past the
first modes, so ``A`` is indefinite) of three kinds of structure at 1e3-1e5 DOF: a shaft chain
(Timoshenko beams, 6 DOF per node), a plate (one layer of hexahedra: a 2-D mesh graph) and a
solid block (3-D). Each (case, backend) runs in its own process: the analysis (ordering)
once, then a timed numeric factorization reusing it, a solve, and the peak resident memory
above the process before the factorization. Agreement: the largest relative difference of the
solutions from the fastest backend's, and the relative residual ``||A x - b|| / ||b||``.

``(auto)`` marks the backend ``sparse_backend="auto"`` takes for the pattern (by its envelope
work, :func:`rheolin.linalg.direct.auto_backend`). The solve column is why it gives cheap
patterns to SuperLU, whose factorizations are as fast there: an iterative method pays a solve
per harmonic and iteration. In a run on 2 cores (``bench/results/backends.md``), at 1e3-1e4
DOF on the chain and at 1e3 on the plate and the solid, SuperLU's solve cost 1.8-5.3x less per
call than UMFPACK's and 3.5-14x less than PARDISO's (0.5-2.9 ms more per solve).

Usage::

    OPENBLAS_NUM_THREADS=1 python bench/backends.py [--sizes 1e3,1e4,1e5] [--timeout 300]
        [--out bench/results/backends.md]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).parent))
from _memory import reset_peak, status_kb

KINDS = ("chain", "plate", "solid")


def build(kind: str, target: int) -> sp.csc_array:
    """The complex block of ``kind`` with about ``target`` DOF."""
    from rheolin.fe.solid import solid_model, tensor_block

    w = 2 * np.pi * 800.0
    if kind == "chain":
        from rheolin import Model

        nodes = max(2, target // 6)
        m = Model()
        m.add_shaft(
            "s", np.linspace(0.0, 0.002 * nodes, nodes), outer_diameter=0.05, material="steel"
        )
        m.add_bearing("a", "s", 0, 1e8, 0.0, components=None)
        a = m.assemble(100.0)
        K, M = a.system.K[0], a.system.M[0]
    else:
        if kind == "plate":
            nx = max(2, round(np.sqrt(target / 6)) - 1)
            size, cells = (0.01 * nx, 0.01 * nx, 0.01), (nx, nx, 1)
        else:
            nx = max(2, round((target / 3) ** (1 / 3)) - 1)
            size, cells = (0.01 * nx,) * 3, (nx,) * 3
        fe = solid_model(*tensor_block(size, cells))
        keep = np.flatnonzero(fe.coordinates[fe.dof_node, 0] > 1e-9)  # clamp the face x = 0
        K = fe.K[keep][:, keep]
        M = fe.M[keep][:, keep]
    A = sp.csc_array(K - w * w * M + 1j * w * 1e-5 * K)
    A.sort_indices()
    return A


def run_one(kind: str, target: int, backend: str, queue: mp.Queue) -> None:
    from rheolin.linalg.direct import analyze

    A = build(kind, target)
    b = np.random.default_rng(0).standard_normal(A.shape[0]) + 0j
    base = status_kb("VmRSS")
    reset_peak()
    t0 = time.perf_counter()
    an = analyze(backend, A.indptr, A.indices, True, sample=A.data)
    t1 = time.perf_counter()
    f = an.factor(A.data)
    t2 = time.perf_counter()
    x = f.solve(b)
    for _ in range(19):  # per-call cost: what an iterative method pays at every iteration
        f.solve(b)
    t3 = time.perf_counter()
    peak = status_kb("VmHWM") - base
    from rheolin.linalg.direct import auto_backend, envelope_work

    res = float(np.linalg.norm(A @ x - b) / np.linalg.norm(b))
    np.save(f"/tmp/rheolin_bench_{kind}_{target}_{backend}.npy", x)
    queue.put(
        dict(
            n=A.shape[0],
            nnz=A.nnz,
            analysis=t1 - t0,
            factor=t2 - t1,
            solve=(t3 - t2) / 20,
            auto=auto_backend(A.indptr, A.indices, A.shape[0]),
            work=envelope_work(A.indptr, A.indices, A.shape[0]),
            peak_mb=peak / 1024,
            residual=res,
            estimate_mb=an.factor_bytes / 1e6,
        )
    )


def measure(kind: str, target: int, backend: str, timeout: float) -> dict | None:
    ctx = mp.get_context("spawn")
    q = ctx.Queue()
    p = ctx.Process(target=run_one, args=(kind, target, backend, q))
    p.start()
    p.join(timeout)
    if p.is_alive():
        p.kill()
        p.join()
        return None
    return q.get() if not q.empty() else None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default="1e3,1e4,1e5")
    ap.add_argument("--kinds", default=",".join(KINDS))
    ap.add_argument("--backends", default="pardiso,umfpack,superlu")
    ap.add_argument("--timeout", type=float, default=300.0)
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    sizes = [int(float(s)) for s in args.sizes.split(",")]
    backends = args.backends.split(",")
    lines = [
        "| structure | DOF | nnz | envelope work | backend | analysis [s] | factor [s] | "
        "solve [ms] (mean of 20) | peak MB | residual | vs fastest | factor / fastest |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    raw = {}
    for kind in args.kinds.split(","):
        for target in sizes:
            rows = {}
            for be in backends:
                r = measure(kind, target, be, args.timeout)
                rows[be] = r
                print(kind, target, be, json.dumps(r), flush=True)
            done = {k: v for k, v in rows.items() if v}
            if not done:
                continue
            best = min(done, key=lambda k: done[k]["factor"])
            xb = np.load(f"/tmp/rheolin_bench_{kind}_{target}_{best}.npy")
            for be in backends:
                r = rows[be]
                if r is None:
                    lines.append(
                        f"| {kind} | ~{target:.0e} | | | {be} | > {args.timeout:.0f} (timeout) "
                        "| | | | | | |"
                    )
                    continue
                x = np.load(f"/tmp/rheolin_bench_{kind}_{target}_{be}.npy")
                diff = float(np.abs(x - xb).max() / np.abs(xb).max())
                pick = " (auto)" if r["auto"] == be else ""
                lines.append(
                    f"| {kind} | {r['n']} | {r['nnz']} | {r['work']:.1e} | {be}{pick} | "
                    f"{r['analysis']:.3g} | {r['factor']:.3g} | {1e3 * r['solve']:.3g} | "
                    f"{r['peak_mb']:.0f} | "
                    f"{r['residual']:.1e} | {diff:.1e} | {r['factor'] / done[best]['factor']:.2g} |"
                )
            raw[f"{kind}_{target}"] = rows
            for f in Path("/tmp").glob(f"rheolin_bench_{kind}_{target}_*.npy"):
                f.unlink()
    header = (
        f"Machine: {os.cpu_count()} cores; MKL_NUM_THREADS={os.environ.get('MKL_NUM_THREADS')}, "
        f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}\n\n"
    )
    text = header + "\n".join(lines) + "\n"
    print(text)
    if args.out:
        Path(args.out).write_text(
            f"`python bench/backends.py --sizes {args.sizes} --timeout {args.timeout:g}`\n\n" + text
        )


if __name__ == "__main__":
    main()
