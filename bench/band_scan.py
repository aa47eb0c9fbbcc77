"""Where the small-gain bound of a band's modes left out is largest (not a test).

For the example gearbox with finely meshed shafts at 3000 rpm, each band size given is
computed (``BandAveraged``) and scanned in the energy norm over the whole grid (no early stop,
as ``Scan.scan`` with an infinite stop): the largest ``kappa_C``, where it is, the band's
radius and the CPU seconds. ``--split`` evaluates the loop at a few frequencies for other
splits of the band's ``1/s`` tail (``rheolin.floquet.scan.SPLIT``) with the last band.

Usage::

    OPENBLAS_NUM_THREADS=1 python bench/band_scan.py --dof 2600 --modes 40 80 160 320
    OPENBLAS_NUM_THREADS=1 python bench/band_scan.py --dof 20000 --modes 40 80 --split
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rheolin.data.fine import refined_example
from rheolin.floquet import band as B
from rheolin.floquet import scan as C
from rheolin.io import parse_model


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dof", type=int, default=2600)
    ap.add_argument("--modes", type=int, nargs="+", default=[40, 80, 160])
    ap.add_argument("--rpm", type=float, default=3000.0)
    ap.add_argument("--split", action="store_true")
    args = ap.parse_args()
    lm = parse_model(refined_example("gearbox", dof=args.dof))
    system = lm.model.speed_template().assemble(args.rpm * np.pi / 30).system
    print(f"gearbox, {system.n:,} DOF, {args.rpm:g} rpm")
    band = None
    for k in args.modes:
        t = time.process_time()
        band = B.BandAveraged(system, k)
        arnoldi = time.process_time() - t
        t = time.process_time()
        scan = C.Scan(system, band)
        out = scan.scan(B._top_frequency(system, band), float("inf"), ("energy",))["energy"]
        print(
            f"{k} modes asked, {band.lam.size} in the band (radius {band.radius:.4g} rad/s, "
            f"Arnoldi {arnoldi:.1f} s): largest "
            f"kappa_C {out.kappa:.4f} at {out.at:.3g} rad/s, {out.points} points, "
            f"{time.process_time() - t:.1f} s",
            flush=True,
        )
    if args.split and band is not None:
        points = [1.6e5, 3e6, 2.8e8, 1.1e10, B._top_frequency(system, band)]
        kept = C.SPLIT
        for split in (1.0, 3.0, 10.0, 30.0, 100.0, 1000.0):
            C.SPLIT = split
            scan = C.Scan(system, band)
            row = []
            for w in points:
                kappa, _ = scan._energy(scan.factor(w), 1j * w)
                row.append(f"{w:.2g}: {kappa:.4f}")
            print(f"SPLIT {split:g}: " + ", ".join(row), flush=True)
        C.SPLIT = kept


if __name__ == "__main__":
    main()
