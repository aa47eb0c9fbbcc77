"""The solve's memory estimate against the measured peak, and the refusal of a problem that
cannot fit (not a test).

A clamped 3-D solid block (scikit-fem hexahedra, the housing stand-in of bench/backends.py)
under a harmonic load, solved with ``lti`` over ``--harmonics`` harmonics in a fresh process:
the estimate (``Solution.info["memory_estimate"]``: factors held + Krylov + vectors, made
before anything large is allocated) against the peak resident memory above the process
before the solve. Then the same block over 100x the harmonics under a 2 GB budget: refused,
and how long the refusal took.

Usage::

    OPENBLAS_NUM_THREADS=1 python bench/memory.py --cells 14 --harmonics 41 \
        --out bench/results/memory.md
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import rheolin as rl
from _memory import reset_peak, status_kb
from rheolin.budget import MemoryBudgetError
from rheolin.fe.solid import solid_model, tensor_block


def block(cells: int) -> rl.PeriodicSystem:
    fe = solid_model(*tensor_block((0.1, 0.1, 0.1), (cells,) * 3), elastic_modulus=2.1e11,
                     poisson_ratio=0.3, density=7850.0)  # fmt: skip
    keep = np.flatnonzero(fe.coordinates[fe.dof_node, 0] > 1e-9)  # clamp the face x = 0
    K, M = fe.K[keep][:, keep].tocsc(), fe.M[keep][:, keep].tocsc()
    f = np.zeros(K.shape[0], complex)
    f[-1] = 1.0
    return rl.PeriodicSystem(2 * np.pi * 50.0, M={0: M}, D={0: 1e-5 * K}, K={0: K}, f={1: f})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cells", type=int, default=14)
    ap.add_argument("--harmonics", type=int, default=41)
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    s = block(args.cells)
    H = rl.HarmonicSet.full((args.harmonics - 1) // 2)
    base = status_kb("VmRSS")
    reset_peak()
    t0 = time.perf_counter()
    sol = rl.solve(s, H, method="lti", stability=False)
    t = time.perf_counter() - t0
    peak = (status_kb("VmHWM") - base) * 1024
    est = float(sol.info["memory_estimate"])
    big = rl.HarmonicSet.full(100 * (args.harmonics - 1) // 2)
    t0 = time.perf_counter()
    try:
        rl.solve(s, big, method="lti", stability=False, memory_budget="2 GB")
        refused = "not refused"
    except MemoryBudgetError as exc:
        refused = f"refused in {time.perf_counter() - t0:.2f} s: {str(exc)[:160]}..."
    text = (
        f"# Solve memory: estimate against measurement\n\n"
        f"`OPENBLAS_NUM_THREADS=1 python bench/memory.py --cells {args.cells} --harmonics "
        f"{args.harmonics}`\n\n| | value |\n|---|---|\n"
        f"| model | clamped solid block, {s.n:,} DOF, {len(H)} harmonics, "
        f"backend {sol.info.get('sparse_backend', sol.info.get('backend', '-'))} |\n"
        f"| solve | {t:.1f} s, success {sol.success} |\n"
        f"| estimate (before allocating) | {est / 1e6:.0f} MB |\n"
        f"| measured peak above the process | {peak / 1e6:.0f} MB |\n"
        f"| estimate / measured | {est / peak:.2f} |\n"
        f"| {len(big):,} harmonics under a 2 GB budget | {refused} |\n"
    )
    print(text)
    if args.out:
        Path(args.out).write_text(text)


if __name__ == "__main__":
    main()
