"""The cost model behind ``backend="auto"`` for ``A0(n)^-1``, measured (not a test).

:func:`rheolin.linalg.backend.choose_backend` takes the modal resolvent when one dense
eigendecomposition of the ``2N`` first-order pencil costs less than a quarter of one sparse LU
per harmonic. It predicts both from two constants: ``EIG_SECONDS_PER_FLOP`` (seconds per
``(2N)^3`` of the eigendecomposition) and ``LU_SECONDS_PER_BLOCK`` (one SuperLU factor and
solve of a small block, SciPy's overhead included). This script measures both side by side
in one process (CPU time of the process, best of 3, one BLAS thread) and prints them beside
the constants:

1. ``scipy.linalg.eig`` of a dense nonsymmetric ``2N x 2N`` matrix for each ``--sizes`` N:
   seconds per ``(2N)^3``;
2. the embedded gearbox at 3000 rpm (its ``A0(n)`` over the file's harmonic set):
   ``LUInverse`` with SuperLU (a factor per harmonic, then one solve of every harmonic) per
   harmonic, and ``ModalInverse`` (the eigendecomposition and its accuracy probes, then one
   solve) once.

The constants were set from a run on 2 cores (one BLAS thread): eigendecomposition about
1.5e-9 (2N)^3 s, one SuperLU factor and solve of a small block about 3e-4 s.

Usage::

    OPENBLAS_NUM_THREADS=1 python bench/block_inverse.py [--sizes 63,126,252,500]
        [--out bench/results/block_inverse.md]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np
import scipy.linalg as sla

RPM = np.pi / 30


def best_of(fn, repeat: int = 3) -> float:  # type: ignore[no-untyped-def]
    """Shortest CPU time of this process over ``repeat`` calls of ``fn()`` (one BLAS thread:
    the wall time of an idle machine, whatever else runs on this one)."""
    best = float("inf")
    for _ in range(repeat):
        t = time.process_time()
        fn()
        best = min(best, time.process_time() - t)
    return best


def eig_rate(N: int) -> float:
    """Seconds per ``(2N)^3`` of a dense nonsymmetric eigendecomposition of size ``2N``."""
    rng = np.random.default_rng(N)
    H = rng.standard_normal((2 * N, 2 * N))
    seconds = best_of(lambda: sla.eig(H, check_finite=False))
    return seconds / (2 * N) ** 3


def gearbox() -> dict[str, float]:
    """Both inverses of the embedded gearbox's ``A0(n)`` at 3000 rpm, timed."""
    from rheolin.data import example_path
    from rheolin.harmonics import HarmonicBalance
    from rheolin.io import load_model
    from rheolin.linalg.lu import LUInverse
    from rheolin.linalg.modal import ModalInverse
    from rheolin.results.compute import harmonic_set

    a = load_model(example_path("gearbox")).assemble(3000 * RPM)
    op = HarmonicBalance(a.system, harmonic_set(a, 3, 200.0))
    ns, R = op.pos, op.rhs

    def lu() -> None:
        LUInverse(op.pencil, ns, sparse_backend="superlu").solve(R)

    def modal() -> None:
        ModalInverse(op.pencil, ns).solve(R)

    return {
        "n": float(op.n_dof),
        "harmonics": float(ns.size),
        "lu": best_of(lu),
        "modal": best_of(modal),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="63,126,252,500", help="N of the 2N x 2N eigenproblems")
    ap.add_argument("--out", type=Path, default=None, help="write the results (markdown)")
    args = ap.parse_args()
    from rheolin.linalg.backend import EIG_SECONDS_PER_FLOP, LU_SECONDS_PER_BLOCK, choose_backend

    lines = [
        "# Cost model of the A0(n) inverse (`backend='auto'`)",
        "",
        f"Command: `python bench/block_inverse.py --sizes {args.sizes}`  ",
        f"Machine: {os.cpu_count()} cores; load average {os.getloadavg()[0]:.2f} at the start; "
        f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}",
        "",
        "| N | 2N | eig [s] | s per (2N)^3 | constant | measured / constant |",
        "|---|---|---|---|---|---|",
    ]
    for N in (int(x) for x in args.sizes.split(",")):
        rate = eig_rate(N)
        lines.append(
            f"| {N} | {2 * N} | {rate * (2 * N) ** 3:.3g} | {rate:.3g} | "
            f"{EIG_SECONDS_PER_FLOP:.3g} | {rate / EIG_SECONDS_PER_FLOP:.2f} |"
        )
        print(lines[-1], flush=True)
    g = gearbox()
    n, h = int(g["n"]), int(g["harmonics"])
    per_block = g["lu"] / h
    predicted_eig = EIG_SECONDS_PER_FLOP * (2 * n) ** 3
    lines += [
        "",
        f"Embedded gearbox at 3000 rpm: N = {n} DOF, {h} harmonics n >= 0 "
        f"(closure order 3, max_order 200); `choose_backend` -> {choose_backend(n, h)}",
        "",
        "| inverse | measured [s] | per harmonic [s] | cost model [s] | measured / model |",
        "|---|---|---|---|---|",
        f"| SuperLU, factor + solve per harmonic | {g['lu']:.3g} | {per_block:.3g} | "
        f"{h * LU_SECONDS_PER_BLOCK:.3g} | {g['lu'] / (h * LU_SECONDS_PER_BLOCK):.2f} |",
        f"| modal, once (eig + probes + solve) | {g['modal']:.3g} | {g['modal'] / h:.3g} | "
        f"{predicted_eig:.3g} (eig only) | {g['modal'] / predicted_eig:.2f} |",
        "",
        f"Modal against SuperLU on this model: {g['lu'] / g['modal']:.1f}x faster "
        f"(the model requires the eigendecomposition below a quarter of the LUs).",
    ]
    text = "\n".join(lines) + "\n"
    print("\n".join(lines[-8:]))
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text)


if __name__ == "__main__":
    main()
