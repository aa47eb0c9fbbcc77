"""Benchmark of the steady-state methods on a transmission-like system (not a test).

System: a beam-like chain (2 DOF per node, banded sparse CSR stiffness, light Rayleigh
damping) on an elastic foundation, carrying

* a gear mesh: rank-1 stiffness ``k(t) w w^T`` between two nodes, ``k(t)`` a rectangular wave
  at the mesh frequency ``z W`` (``z = 23`` teeth) with ``MESH_HARMONICS`` Fourier harmonics;
* a rotating asymmetric body: a ``±2`` harmonic block on the DOFs of two nodes;
* loads: unbalance at ``±1`` and transmission error at the mesh harmonics.

For each size ``n`` (DOF) and harmonic count ``|H|`` every method runs in a fresh subprocess
(so the peak resident memory includes SuperLU's C allocations, which tracemalloc cannot see):
``lti`` on the time-averaged system (same matrices, only ``k = 0``), then ``perturbation``,
``gmres`` and ``direct`` on the full system, all with ``stability=False``. Each answer is
compared with gmres's.

The beam-like chain has an elastic foundation, so its conditioning does not grow with ``n``
(a finite-element Euler-Bernoulli beam at n = 1e4 has cond(A0) ~ 1e15 and every method's
residual check fails there for conditioning, not for the method).

Usage::

    python bench/solvers.py [--quick] [--out bench/results/solvers.md] [--timeout 900]
    python bench/solvers.py --wide 0.3 --asym 0.5 --out bench/results/solvers_wide.md

Targets: gmres within 1.5x of lti; direct >= 10x slower than gmres from |H| = 201.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from _memory import reset_peak, status_kb

TEETH = 23
MESH_HARMONICS = 6
SPEED = 2 * np.pi * 25.0  # shaft speed [rad/s] = w1

#: Skip ``direct`` above this many coupled unknowns (n |H|): its peak memory grows about
#: linearly with n |H| here (2 GB at 2e6 unknowns) and superlinearly for wider coupling.
DIRECT_MAX_UNKNOWNS = 2_500_000
#: Address-space limit of the ``direct`` measurement subprocess.
MEMORY_LIMIT_GB = 14.0


# --------------------------------------------------------------------------- the system
def beam_system(
    n_dof: int,
    time_varying: bool = True,
    depth: float = 0.3,
    asym: float = 0.05,
    wide: float = 0.0,
):
    """Beam-like chain with gear mesh and asymmetric body; ``time_varying=False`` keeps the
    ``k = 0`` coefficients only (the time-averaged system, same matrices).

    ``wide > 0``: the asymmetric body is a shaft segment spanning that fraction of the nodes
    (every node of it carries a ±2 block of ``asym k_g / 2``), as a non-axisymmetric shaft
    does, instead of two nodes.

    Nodes carry 2 DOF (x, y); nearest-neighbour springs ``k1`` and next-nearest springs ``k2``
    (a bending-like band, bandwidth 4 in DOF) on an elastic foundation ``k_g`` (housing and
    bearings), unit masses, Rayleigh damping with ~2 % in the band of natural frequencies
    (1000..3200 rad/s). The foundation keeps the condition number independent of ``n``.
    """
    import rheolin as rl

    nodes = n_dof // 2
    n = 2 * nodes
    k1, k2, k_g = 2e6, 5e5, 1e6
    rows, cols, vals = [], [], []

    def spring(i: np.ndarray, j: np.ndarray, k: float) -> None:
        rows.extend([i, j, i, j])
        cols.extend([i, j, j, i])
        vals.extend(
            [np.full(i.size, k), np.full(i.size, k), np.full(i.size, -k), np.full(i.size, -k)]
        )

    for d in (0, 1):  # x and y
        dof = 2 * np.arange(nodes) + d
        spring(dof[:-1], dof[1:], k1)
        spring(dof[:-2], dof[2:], k2)
    K0 = sp.coo_array(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
    ).tocsr() + k_g * sp.identity(n, format="csr")
    M0 = sp.identity(n, format="csr")
    D0 = (1.0e-5 * K0 + 20.0 * M0).tocsr()

    # gear mesh between the x DOFs of nodes at 1/3 and 2/3 of the chain
    a, b = 2 * (nodes // 3), 2 * ((2 * nodes) // 3)
    w = np.zeros(n)
    w[a], w[b] = 1.0, -0.8
    ww = sp.csr_array(np.outer(w[[a, b]], w[[a, b]]).ravel().reshape(2, 2))
    ww = sp.csr_array(
        sp.coo_array(
            (ww.toarray().ravel(), (np.repeat([a, b], 2), np.tile([a, b], 2))), shape=(n, n)
        )
    )
    k_mesh, duty = 1e6, 0.6  # mean mesh stiffness, share of double contact
    K: dict[int, object] = {0: (K0 + k_mesh * ww).tocsr()}
    f_te = np.zeros(n, dtype=complex)
    f_te[[a, b]] = k_mesh * 1e-6 * w[[a, b]]  # transmission error of 1 micron
    loads: dict[int, np.ndarray] = {}
    for j in range(1, MESH_HARMONICS + 1):
        # rectangular wave: pulse of height depth * k_mesh over a share `duty` of a mesh
        c = depth * k_mesh * np.sin(np.pi * j * duty) / (np.pi * j)
        if time_varying:
            K[TEETH * j] = (c * ww).tocsr()
        loads[TEETH * j] = f_te * np.sin(np.pi * j * duty) / (np.pi * j)
    # rotating asymmetric body: (x, y) of two nodes near the end, harmonics ±2
    body = np.arange(n - 8, n - 4)
    if time_varying:
        kd = asym * k_g
        block = sp.lil_array((n, n), dtype=complex)
        shape = np.array([[1.0, -1j], [-1j, -1.0]])
        block[np.ix_(body[:2], body[:2])] = kd / 2 * shape
        block[np.ix_(body[2:], body[2:])] = kd / 4 * shape
        for node in range(nodes - 4 - int(wide * nodes), nodes - 4) if wide > 0 else ():
            pair = [2 * node, 2 * node + 1]
            block[np.ix_(pair, pair)] = kd / 2 * shape
        K[2] = sp.csr_array(block)
    f1 = np.zeros(n, dtype=complex)
    f1[body[:2]] = 1e-4 * SPEED**2 * np.array([1.0, -1j]) / 2  # rotating unbalance 1e-4 kg m
    loads[1] = f1
    return rl.PeriodicSystem(SPEED, M={0: M0}, D={0: D0}, K=K, f=loads)


# --------------------------------------------------------------------------- one measurement
def worker(n: int, n_h: int, method: str, out: str, asym: float, wide: float) -> None:
    """Run one method in this (fresh) process; write timing, memory and the answer."""
    import resource

    import rheolin as rl

    if method == "direct":
        # a failed allocation (MemoryError, reported as status 3) instead of the OOM killer;
        # only for direct: the address-space limit also counts SuperLU's and the threads'
        # reserved-but-untouched memory, which made lti fail at n=1e4, |H|=801 at 14 GB.
        limit = int(MEMORY_LIMIT_GB * 2**30)
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    system = beam_system(n, time_varying=method != "lti", asym=asym, wide=wide)
    H = rl.HarmonicSet.full((n_h - 1) // 2)
    base = status_kb("VmRSS")
    peak_reset = reset_peak()
    t0 = time.perf_counter()
    sol = rl.solve(system, H, method=method, stability=False)
    seconds = time.perf_counter() - t0
    peak = status_kb("VmHWM") if peak_reset else _peak_rusage_kb()
    np.save(out + ".npy", sol.q)
    info = {
        "seconds": seconds,
        "iterations": sol.iterations,
        "success": sol.success,
        "status": sol.status,
        "residual": sol.residual,
        "message": sol.message,
        "peak_mb": peak / 1024,
        "extra_mb": (peak - base) / 1024 if peak_reset else float("nan"),
        "strategy": sol.info.get("strategy", ""),
    }
    Path(out + ".json").write_text(json.dumps(info))


def _peak_rusage_kb() -> int:
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def measure(
    n: int, n_h: int, method: str, timeout: float, tmp: str, asym: float, wide: float
) -> dict:
    out = os.path.join(tmp, f"{method}_{n}_{n_h}")
    cmd = [sys.executable, __file__, "--worker", str(n), str(n_h), method, out, str(asym)]
    cmd.append(str(wide))
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"error": f"timeout after {timeout:.0f} s"}
    if proc.returncode != 0:
        tail = (proc.stderr or "").strip().splitlines()[-1:] or [f"exit {proc.returncode}"]
        return {"error": tail[0][:80]}
    info = json.loads(Path(out + ".json").read_text())
    info["wall"] = time.perf_counter() - t0
    info["q_file"] = out + ".npy"
    return info


# --------------------------------------------------------------------------- the table
def _fmt_s(x: dict) -> str:
    if "error" in x:
        return "—"
    flag = "" if x["success"] else f" (status {x['status']})"
    return f"{x['seconds']:.2f}{flag}"


def run(
    sizes: list[int],
    harmonics: list[int],
    timeout: float,
    out: str | None,
    repeat: int = 1,
    asym: float = 0.05,
    wide: float = 0.0,
) -> None:
    header = (
        "| n | \\|H\\| | lti [s] | perturbation [s] (its) | gmres [s] (its) | direct [s] | "
        "gmres/lti | direct/gmres | peak RSS lti/pert/gmres/direct [MB] | "
        "rel. diff vs gmres: pert / direct |"
    )
    lines = [header, "|" + "---|" * 10]
    notes: list[str] = []
    print(header, flush=True)
    with tempfile.TemporaryDirectory(prefix="rheolin-bench-") as tmp:
        for n in sizes:
            for n_h in harmonics:
                res: dict[str, dict] = {}
                for method in ("lti", "gmres", "perturbation", "direct"):
                    if method == "direct" and n * n_h > DIRECT_MAX_UNKNOWNS:
                        res[method] = {"error": "skipped"}
                        notes.append(
                            f"direct skipped at n={n}, |H|={n_h}: {n * n_h:.1e} coupled "
                            f"unknowns > {DIRECT_MAX_UNKNOWNS:.1e} (estimated > 8 GB for the LU "
                            "of the coupled matrix, extrapolated from the smaller runs)"
                        )
                        continue
                    runs = [
                        measure(n, n_h, method, timeout, tmp, asym, wide)
                        for _ in range(max(1, repeat))
                    ]
                    ok = [r for r in runs if "error" not in r]
                    res[method] = min(ok, key=lambda r: r["seconds"]) if ok else runs[0]
                    if "error" in res[method] and method == "direct":
                        notes.append(f"direct at n={n}, |H|={n_h}: {res[method]['error']}")
                    elif "error" in res[method]:
                        notes.append(f"{method} at n={n}, |H|={n_h}: {res[method]['error']}")
                g = res["gmres"]
                q_g = np.load(g["q_file"]) if "q_file" in g else None
                diffs = {}
                for m in ("perturbation", "direct"):
                    r = res[m]
                    if q_g is None or "q_file" not in r:
                        diffs[m] = "—"
                        continue
                    q = np.load(r["q_file"])
                    d = np.linalg.norm(q - q_g) / np.linalg.norm(q_g)
                    diffs[m] = f"{d:.1e}" if np.isfinite(d) else "inf"
                    if not r["success"]:
                        notes.append(f"{m} at n={n}, |H|={n_h}: {r['message'][:140]}")

                def ratio(a: str, b: str, res: dict[str, dict] = res) -> str:
                    ra, rb = res[a], res[b]
                    if "error" in ra or "error" in rb:
                        return "—"
                    return f"{ra['seconds'] / rb['seconds']:.2f}"

                its = {
                    m: (f" ({res[m]['iterations']})" if "iterations" in res[m] else "") for m in res
                }
                mem = "/".join(
                    f"{res[m]['peak_mb']:.0f}" if "peak_mb" in res[m] else "—"
                    for m in ("lti", "perturbation", "gmres", "direct")
                )
                strategy = g.get("strategy", "")
                row = (
                    f"| {n} | {n_h} | {_fmt_s(res['lti'])} | "
                    f"{_fmt_s(res['perturbation'])}{its['perturbation']} | "
                    f"{_fmt_s(g)}{its['gmres']} {strategy} | {_fmt_s(res['direct'])} | "
                    f"{ratio('gmres', 'lti')} | {ratio('direct', 'gmres')} | {mem} | "
                    f"{diffs['perturbation']} / {diffs['direct']} |"
                )
                lines.append(row)
                print(row, flush=True)
                for m in res.values():
                    if "q_file" in m:
                        os.remove(m["q_file"])
    text = "\n".join(lines)
    meta = (
        f"\n\nBeam-like chain with a gear mesh (z = {TEETH}, {MESH_HARMONICS} mesh harmonics, "
        "rank 1) and a ±2 asymmetric-body block "
        + (f"over {wide:.0%} of the nodes " if wide > 0 else "on two nodes ")
        + f"(amplitude {asym} k_g / 2 per node); n DOF, |H| = 2N + 1 harmonics "
        f"(`HarmonicSet.full(N)`). {os.cpu_count()} CPUs, default `workers`, "
        f"`stability=False`, fastest of {repeat} run(s). Peak RSS: the kernel's "
        "high-water mark of a fresh subprocess during the solve (reset after building the "
        "system), so it includes SuperLU's C allocations. lti solves the time-averaged system "
        "(same matrices, k = 0 only)."
    )
    if notes:
        meta += "\n\nNotes:\n" + "\n".join(f"* {x}" for x in dict.fromkeys(notes))
    print(meta)
    if out:
        Path(out).parent.mkdir(parents=True, exist_ok=True)
        Path(out).write_text("# Solver benchmark\n\n" + text + meta + "\n")
        print(f"wrote {out}")


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        n, n_h, method, out, asym, wide = sys.argv[2:8]
        worker(int(n), int(n_h), method, out, float(asym), float(wide))
        return
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--quick", action="store_true", help="small sizes (a smoke run)")
    p.add_argument("--out", help="write a markdown table here")
    p.add_argument("--timeout", type=float, default=900.0, help="seconds per method run")
    p.add_argument("--repeat", type=int, default=1, help="runs per method; the fastest is reported")
    p.add_argument("--sizes", help="comma-separated n (default 1000,10000)")
    p.add_argument("--harmonics", help="comma-separated |H| (default 51,201,801)")
    p.add_argument("--asym", type=float, default=0.05, help="asymmetric block / k_g")
    p.add_argument(
        "--wide", type=float, default=0.0, help="asymmetric shaft segment: fraction of nodes"
    )
    args = p.parse_args()
    sizes, harmonics = [1000, 10000], [51, 201, 801]
    if args.quick:
        sizes, harmonics = [400, 2000], [51, 201]
    if args.sizes:
        sizes = [int(x) for x in args.sizes.split(",")]
    if args.harmonics:
        harmonics = [int(x) for x in args.harmonics.split(",")]
    run(sizes, harmonics, args.timeout, args.out, args.repeat, args.asym, args.wide)


if __name__ == "__main__":
    main()
