"""Memory of one lattice search against its estimate (not a test).

The finely meshed gearbox (``rheolin.data.fine``) at 3000 rpm: its certified band, then one
full lattice search of order ``--order`` from the band, under ``tracemalloc`` (the arrays
Python allocates: the Arnoldi bases, the candidates' and representatives' eigenvectors)
and with the process's peak resident memory reset before it (which also sees the sparse
factors). Beside them, ``lattice_memory`` for the clusters the search had to search and for
:data:`~rheolin.floquet.footprint.TYPICAL_CLUSTERS` (the estimate before the averaged modes
are known), and what the search found: candidates, exponents, eigenvector size.

Usage::

    OPENBLAS_NUM_THREADS=1 python bench/search_memory.py --dof 5000 --order 1 2 \\
        --out bench/results/search_memory.md
"""

from __future__ import annotations

import argparse
import gc
import importlib
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _memory import reset_peak, status_kb
from rheolin.data.fine import refined_example
from rheolin.io import parse_model

search = importlib.import_module("rheolin.floquet.search")
large = importlib.import_module("rheolin.floquet.large")
footprint = importlib.import_module("rheolin.floquet.footprint")
resonance = importlib.import_module("rheolin.floquet.resonance")

GB = 1e9


def row(dof: int, order: int) -> dict[str, float | int]:
    model = parse_model(refined_example("gearbox", dof=dof)).model
    system = model.speed_template().assemble(3000 * np.pi / 30).system
    modes = large.certified_band(system, None, None, order)
    lattice = resonance.floquet_lattice(system, order, max_size=10**6, avg=modes)
    gc.collect()
    base_rss = status_kb("VmRSS")
    reset_peak()
    tracemalloc.start()
    start = tracemalloc.get_traced_memory()[0]
    t = time.process_time()
    run = search.LatticeSearch(system, lattice, modes=modes, defer_truncation=True)
    planned = len(run.clusters) - len(run.skipped)
    candidates: list[int] = []
    original = search.select

    def counted(pool, *args, **kwargs):  # the pool's size when the representatives are chosen
        candidates.append(len(pool))
        return original(pool, *args, **kwargs)

    search.select = counted
    try:
        out = run.run()
    finally:
        search.select = original
    cpu = time.process_time() - t
    peak = tracemalloc.get_traced_memory()[1] - start
    tracemalloc.stop()
    rss = (status_kb("VmHWM") - base_rss) * 1024
    return {
        "dof": system.n,
        "order": order,
        "harmonics": len(lattice),
        "vector_mb": 2 * system.n * len(lattice) * 16 / 1e6,
        "clusters": planned,
        "candidates": candidates[-1] if candidates else 0,
        "exponents": int(out.exponents.size),
        "cpu": cpu,
        "traced_gb": peak / GB,
        "rss_gb": rss / GB,
        "estimate_gb": footprint.lattice_memory(system, lattice, clusters=planned) / GB,
        "typical_gb": footprint.lattice_memory(system, lattice) / GB,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dof", type=int, nargs="+", default=[5000])
    parser.add_argument("--order", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    head = (
        "| DOF | order | harmonics | vector MB | clusters | candidates | exponents | CPU s "
        "| traced peak GB | RSS peak GB | estimate GB | estimate (typical) GB |"
    )
    lines = [head, "|" + "---|" * 12]
    for dof in args.dof:
        for order in args.order:
            r = row(dof, order)
            lines.append(
                f"| {r['dof']:,} | {r['order']} | {r['harmonics']} | {r['vector_mb']:.1f} "
                f"| {r['clusters']} | {r['candidates']} | {r['exponents']} | {r['cpu']:.1f} "
                f"| {r['traced_gb']:.3f} | {r['rss_gb']:.3f} | {r['estimate_gb']:.3f} "
                f"| {r['typical_gb']:.3f} |"
            )
            print(lines[-1], flush=True)
    text = "\n".join(lines) + "\n"
    if args.out:
        args.out.write_text(
            "# Lattice search memory against its estimate\n\n"
            f"`OPENBLAS_NUM_THREADS=1 python bench/search_memory.py --dof "
            f"{' '.join(map(str, args.dof))} --order {' '.join(map(str, args.order))}`\n\n" + text
        )


if __name__ == "__main__":
    main()
