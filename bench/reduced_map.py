"""A stability map of the finely meshed gearbox on its Craig-Bampton reduction, and the
full model's verdict at a few of its speeds (docs/stability.md, section 9).

    OPENBLAS_NUM_THREADS=1 python bench/reduced_map.py --dof 20000 --speeds 2000 5980 200 \
        --check 3000 --out bench/results/reduced_map.md

Wall time of the map on ``--workers`` worker processes (the speed template, the basis and
every verdict included), the CPU seconds of this process and its workers, and at each
``--check`` speed the full system's verdict (the band of section 8) beside the map's.
"""

from __future__ import annotations

import argparse
import resource
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

import rheolin as rl
from rheolin.data.fine import refined_example
from rheolin.io import parse_document
from rheolin.stability.stability_map import stability_map


def cpu() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--dof", type=int, default=20000, help="shaft DOFs of the gearbox")
    ap.add_argument("--speeds", type=float, nargs=3, default=[2000.0, 5980.0, 200],
                    metavar=("FIRST", "LAST", "COUNT"), help="rpm")  # fmt: skip
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--check", type=float, nargs="*", default=[3000.0], help="rpm")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    model = parse_document(tomllib.loads(refined_example("gearbox", dof=args.dof))).model
    first, last, count = args.speeds
    rpm = np.linspace(first, last, int(count))
    seen: list[tuple[float, float, int, float]] = []  # arrival, cut-off, modes, seconds

    def progress(i: int, res: rl.FloquetResult) -> None:
        red = res.info.get("reduction", {})
        seen.append((time.perf_counter() - t0, red.get("cutoff", np.nan),
                     red.get("modes", -1), res.info.get("seconds", np.nan)))  # fmt: skip
        if len(seen) % 20 == 0:
            print(f"  {len(seen)}/{rpm.size} speeds at {seen[-1][0]:.0f} s", flush=True)

    c0, t0 = cpu(), time.perf_counter()
    smap = stability_map(
        model,
        rpm * np.pi / 30,
        reduce=True,
        workers=args.workers,
        identify_mechanism=False,
        progress=progress,
    )
    wall, used = time.perf_counter() - t0, cpu() - c0
    cutoffs = sorted({c for _, c, _, _ in seen})
    modes = sorted({m for _, _, m, _ in seen})
    per = np.array([s for _, _, _, s in seen])
    mr = np.asarray(smap.max_real)
    unc = np.asarray(smap.max_real_uncertainty)
    n = model.assemble(float(rpm[0]) * np.pi / 30).system.n
    lines = [
        f"# Stability map of the gearbox with {n:,}-DOF shafts on its Craig-Bampton reduction",
        "",
        f"`OPENBLAS_NUM_THREADS=1 python bench/reduced_map.py {' '.join(sys.argv[1:])}`",
        "",
        "| map | result |",
        "|---|---|",
        f"| speeds | {rpm.size}, {first:g}-{last:g} rpm, {smap.info.get('continued')} continued |",
        f"| wall time | {wall:.0f} s on {args.workers} workers ({used:.0f} CPU s) |",
        f"| a verdict (median, max) | {np.nanmedian(per):.1f} s, {np.nanmax(per):.1f} s |",
        f"| cut-offs used | {', '.join(f'{c:.3g}' for c in cutoffs)} rad/s "
        f"({', '.join(str(m) for m in modes)} modes) |",
        f"| undecided speeds | {int(np.sum(smap.undecided))} |",
        f"| unstable ranges | {len(smap.ranges)} |",
        f"| largest real part | {mr.min():.6f} to {mr.max():.6f} 1/s |",
        f"| its stated uncertainty | {unc.min():.2g} to {unc.max():.2g} 1/s |",
        "",
        "| rpm | map (reduced) | full system (band, section 8) | full CPU s |",
        "|---|---|---|---|",
    ]
    for r in args.check:
        i = int(np.argmin(np.abs(rpm - r)))
        s = model.assemble(float(rpm[i]) * np.pi / 30).system
        c = time.process_time()
        full = rl.floquet(s)
        dt = time.process_time() - c
        lines.append(
            f"| {rpm[i]:.1f} | {mr[i]:.6f} +- {unc[i]:.2g} | {full.max_real:.6f} +- "
            f"{full.max_real_uncertainty:.2g} (decided {full.decided}) | {dt:.0f} |"
        )
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        Path(args.out).write_text(text)
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
