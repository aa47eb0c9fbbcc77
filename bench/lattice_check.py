"""Lattice Floquet against the dense Hill method on random variants of the example rotor.

Each variant draws the bearing stiffness (x, y and cross-coupled), the bearing damping, the
flatted shaft's second asymmetry and the speed (half of them inside or near the
asymmetric-shaft band, where 2 x speed ~ a bending frequency); the default verdict of
``rl.floquet(system, method="lattice")`` is compared with the dense Hill method on
-12..12 (QZ of the whole Hill matrix, a different truncation and algorithm). Counted:

* wrong verdicts: both decided (dense also converged) and stable/unstable differ;
* the largest real part, against dense: the worst difference relative to
  ``max(|Re|, 1e-3 |lambda|)``.

Run: ``python bench/lattice_check.py --variants 200 --out bench/results/lattice_check.md``.
"""

from __future__ import annotations

import argparse
import time
import tomllib
from pathlib import Path

import numpy as np
import scipy.linalg as sla

import rheolin as rl
from rheolin.data import example_path
from rheolin.harmonics.hill import hill_pencil
from rheolin.io import parse_document


def variant(rng: np.random.Generator) -> tuple[str, dict[str, float]]:
    kx = 10 ** rng.uniform(6.5, 8)
    ky = kx * rng.uniform(0.5, 1.0)
    kc = kx * rng.uniform(0, 0.2)
    c = 10 ** rng.uniform(1.5, 3.5)
    iz = 3.55 * rng.uniform(1.01, 1.3)
    text = (
        example_path("rotor")
        .read_text()
        .replace(
            '"5e7 N/m", "4e7 N/m", "5e7 N/m"', f'"{kx:.4g} N/m", "{ky:.4g} N/m", "{kx:.4g} N/m"'
        )
        .replace(
            '[["5e7 N/m", "5e6 N/m"], ["5e6 N/m", "4e7 N/m"]]',
            f'[["{kx:.4g} N/m", "{kc:.4g} N/m"], ["{kc:.4g} N/m", "{ky:.4g} N/m"]]',
        )
        .replace(
            '"500 N*s/m", "500 N*s/m", "500 N*s/m"', f'"{c:.4g} N*s/m", ' * 2 + f'"{c:.4g} N*s/m"'
        )
        .replace(
            'damping = ["500 N*s/m", "500 N*s/m"]', f'damping = ["{c:.4g} N*s/m", "{c:.4g} N*s/m"]'
        )
        .replace('Iz = "3.98 cm^4"', f'Iz = "{iz:.4g} cm^4"')
    )
    return text, {"kx": kx, "ky": ky, "kc": kc, "c": c, "Iz": iz}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variants", type=int, default=100)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    rows, wrong, worst, t_lat, t_dense = [], 0, 0.0, 0.0, 0.0
    undecided = 0
    t0 = time.perf_counter()
    for i in range(args.variants):
        text, _ = variant(rng)
        model = parse_document(tomllib.loads(text)).model
        if i % 2:
            rpm = float(rng.uniform(500, 9000))
        else:  # near the band: 2 x speed ~ the first bending frequency of the averaged system
            s0 = model.assemble(3000 * np.pi / 30).system
            A, B = hill_pencil(s0, [0])  # the time-averaged system (harmonic 0 only)
            lam0 = sla.eigvals(A.toarray(), B.toarray())
            lam0 = lam0[np.isfinite(lam0)]
            # (the rigid torsion on its 1e4 N m/rad spring sits lower, near 50 rad/s)
            wb = np.sort(np.abs(lam0.imag[np.abs(lam0.imag) > 200]))[0]
            rpm = float(wb / 2 * rng.uniform(0.95, 1.05) * 30 / np.pi)
        system = model.assemble(rpm * np.pi / 30).system
        t = time.perf_counter()
        lat = rl.floquet(system, method="lattice")
        t_lat += time.perf_counter() - t
        t = time.perf_counter()
        dense = rl.floquet(system, 12)
        t_dense += time.perf_counter() - t
        both = lat.decided and dense.decided and dense.converged
        bad = both and lat.stable != dense.stable
        wrong += int(bad)
        undecided += int(not lat.decided)
        lead = dense.exponents[0] if dense.exponents.size else 0j
        scale = max(abs(dense.max_real), 1e-3 * abs(lead))
        diff = abs(lat.max_real - dense.max_real) / scale if both else float("nan")
        if both:
            worst = max(worst, diff)
        rows.append((i, rpm, dense.max_real, lat.max_real, lat.decided, dense.decided, diff, bad))
        print(
            f"{i:4d} {rpm:7.0f} rpm dense {dense.max_real:+.6e} lattice {lat.max_real:+.6e} "
            f"{'decided' if lat.decided else 'undecided'} diff {diff:.1e}"
            f"{'  WRONG' if bad else ''}",
            flush=True,
        )
    total = time.perf_counter() - t0
    lines = [
        "# Lattice Floquet against dense Hill, random variants of the example rotor",
        "",
        f"`python bench/lattice_check.py --variants {args.variants} --seed {args.seed}`; "
        f"{total:.0f} s in all (lattice {t_lat:.0f} s, dense {t_dense:.0f} s).",
        "",
        "| | value |",
        "|---|---|",
        f"| variants | {args.variants} (half within 5 % of the asymmetric-shaft band) |",
        f"| wrong verdicts (both decided) | **{wrong}** |",
        f"| lattice undecided | {undecided} |",
        f"| largest real part, worst difference / max(\\|Re\\|, 1e-3 \\|lambda\\|) | {worst:.1e} |",
        "",
        "| # | rpm | dense max Re [1/s] | lattice max Re [1/s] | lattice decided | difference |",
        "|---|---|---|---|---|---|",
    ]
    for i, rpm, d, la, dec, _, diff, bad in rows:
        mark = " **wrong**" if bad else ""
        lines.append(f"| {i} | {rpm:.0f} | {d:+.6e} | {la:+.6e} | {dec} | {diff:.1e}{mark} |")
    if args.out:
        args.out.write_text("\n".join(lines) + "\n")
    print(
        f"wrong {wrong} of {args.variants}; worst {worst:.1e}; undecided {undecided}; {total:.0f} s"
    )


if __name__ == "__main__":
    main()
