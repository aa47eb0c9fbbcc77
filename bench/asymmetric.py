"""Non-axisymmetric rotors: gmres against the time-invariant floor, over the catalogue.

The catalogue of tests/core/asymmetric.py (Delta K / K 1-20 %, asymmetric over 10-100 % of
the shaft, damping 0.5-5 %, speeds below, inside and above the band of modes) at a chosen
size. Per case, side by side in this process: ``lti`` on the time-averaged system (the same
matrices, ``k = 0`` only: the floor), then ``rl.solve`` with ``method="auto"`` on the full
system; the ratio of their times, gmres's strategy and iterations, and whether ``auto`` had
to fall back to ``direct``.

Usage::

    OPENBLAS_NUM_THREADS=1 python bench/asymmetric.py --nodes 500 --out bench/results/asymmetric.md
    OPENBLAS_NUM_THREADS=1 python bench/asymmetric.py --nodes 5000 --fractions 0.3 \
        --asymmetries 0.05,0.2 --out bench/results/asymmetric_1e4.md
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parents[1] / "tests" / "core"))
import rheolin as rl
from asymmetric import ASYMMETRIES, DAMPINGS, FRACTIONS, SPEEDS, shaft


def floor(system: rl.PeriodicSystem) -> rl.PeriodicSystem:
    return rl.PeriodicSystem(
        system.omega, M={0: system.M[0]}, D={0: system.D[0]}, K={0: system.K[0]}, f=system.f
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--nodes", type=int, default=500, help="2 DOF per node")
    ap.add_argument("--asymmetries", default=",".join(map(str, ASYMMETRIES)))
    ap.add_argument("--fractions", default=",".join(map(str, FRACTIONS)))
    ap.add_argument("--out", default=None)
    ap.add_argument(
        "--no-planes",
        action="store_true",
        help="leave out the nodes' (x, y) planes (no whirl-pair preconditioner): the A0 strategies",
    )
    args = ap.parse_args()
    asyms = [float(x) for x in args.asymmetries.split(",")]
    fracs = [float(x) for x in args.fractions.split(",")]
    rows, t_all = [], time.perf_counter()
    for a, frac, zeta, W in itertools.product(asyms, fracs, DAMPINGS, SPEEDS):
        s, H = shaft(args.nodes, a, frac, zeta, W, planes=not args.no_planes)
        rl.solve(floor(s), H, method="lti", stability=False)  # warm: imports, analysis cache
        t0 = time.perf_counter()
        rl.solve(floor(s), H, method="lti", stability=False)
        t_lti = time.perf_counter() - t0
        t0 = time.perf_counter()
        sol = rl.solve(s, H, stability=False)
        t_auto = time.perf_counter() - t0
        row = dict(
            a=a, frac=frac, zeta=zeta, W=W, nh=len(H), lti=t_lti, auto=t_auto,
            ratio=t_auto / t_lti, method=sol.method, strategy=sol.info.get("strategy", "-"),
            its=sol.iterations, ok=sol.success, residual=sol.residual,
        )  # fmt: skip
        rows.append(row)
        print(
            f"{a:5.2f} {frac:4.1f} {zeta:5.3f} {W:6.0f} |H|={len(H):3d} lti {t_lti:7.3f} s "
            f"auto {t_auto:7.3f} s x{row['ratio']:6.1f} {sol.method}/{row['strategy']} "
            f"{sol.iterations} its ok={sol.success}",
            flush=True,
        )
    ratios = np.array([r["ratio"] for r in rows])
    local = np.array([r["frac"] <= 0.3 and r["strategy"] == "support" for r in rows])
    fell_back = sum(r["method"] != "gmres" for r in rows)
    failed = sum(not r["ok"] for r in rows)
    head = (
        f"# Non-axisymmetric catalogue at {2 * args.nodes} DOF\n\n"
        f"`OPENBLAS_NUM_THREADS=1 python bench/asymmetric.py --nodes {args.nodes} "
        f"--asymmetries {args.asymmetries} --fractions {args.fractions}"
        f"{' --no-planes' if args.no_planes else ''}`; "
        f"{len(rows)} cases, {time.perf_counter() - t_all:.0f} s in all.\n\n"
        f"| | value |\n|---|---|\n"
        f"| cases not converged | {failed} |\n"
        f"| fallbacks to `direct` | {fell_back} |\n"
        f"| auto / lti, median | {np.median(ratios):.1f} |\n"
        f"| auto / lti, worst | {ratios.max():.1f} |\n"
        f"| auto / lti, worst with the support strategy | "
        f"{ratios[local].max() if local.any() else float('nan'):.1f} |\n"
        f"| strategies | {', '.join(sorted({r['strategy'] for r in rows}))} |\n\n"
        "| Delta K / K | extent | zeta | W [rad/s] | harmonics | lti [s] | auto [s] | ratio "
        "| method / strategy | iterations | converged |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|\n"
    )
    body = "".join(
        f"| {r['a']:.2f} | {r['frac']:.1f} | {r['zeta']:.3f} | {r['W']:.0f} | {r['nh']} | "
        f"{r['lti']:.3f} | {r['auto']:.3f} | {r['ratio']:.1f} | {r['method']} / "
        f"{r['strategy']} | {r['its']} | {r['ok']} |\n"
        for r in rows
    )
    print(head.split("| Delta")[0])
    if args.out:
        Path(args.out).write_text(head + body)
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
