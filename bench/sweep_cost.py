"""Per-speed cost of a steady-state solve, before/after, and against ROSS (not a test).

(a) The embedded gearbox (126 DOF, closure order 3, ``max_order`` 200: 2,945 harmonics) at a
    few speeds around 3000 rpm: assembly, solve (``stability=False``) and outputs (the point
    dataset with bearing forces and DTE), per speed, for the code *before* (a source tree at
    commit 1724902, extracted with ``git archive`` into a temporary directory) and *after*
    (this tree: one ``SpeedTemplate``, each speed warm-started from the previous one). Answers
    must agree to 1e-9.
(b) ROSS 2.3's ``rotor_example`` (6 Timoshenko elements, 2 disks, 2 bearings; 42 DOF) rebuilt
    with ``rheolin.Model`` from the data in ROSS's source; unbalance response at 1,000 speeds:
    ROSS ``run_unbalance_response`` against rheolin's batched ``lti_speeds`` and against a
    Python loop of ``template.assemble`` + ``rl.solve`` (the general API). ROSS applies the
    unbalance as a force ``U W^2`` (rheolin's disk unbalance is the exact linearization with a
    rotating centre of mass, docs/rotating-bodies.md, which differs at O(c^2)), so rheolin gets
    the same
    force here. Responses must agree to 1e-9.
(c) Resident memory over 500 ``rl.solve`` calls (a 1000-DOF chain with a gear mesh, 51
    harmonics, gmres) with the default workers, before and after.

Every measurement runs in its own subprocess (peak RSS from ``/proc``, see ``_memory.py``).

Usage (needs the ``bench`` extra for ROSS: ``pip install -e '.[bench]'``)::

    OPENBLAS_NUM_THREADS=1 python bench/sweep_cost.py [--out bench/results/sweep_cost.md]
        [--before DIR] [--ross-speeds 1000] [--rss-solves 500] [--skip-rss]
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

from _memory import reset_peak, status_kb

HERE = Path(__file__).resolve().parent
BEFORE_COMMIT = "1724902"
RPMS = (2900.0, 2950.0, 3000.0, 3050.0)
ROSS_RANGE = (10.0, 1000.0)  # rad/s; both critical speeds of the example (92-297 rad/s) inside


# --------------------------------------------------------------------------- workers
def _gearbox(out: str) -> dict:
    import rheolin as rl
    from rheolin.data import example_path
    from rheolin.io import load_model
    from rheolin.results.compute import OperatingPoint, harmonic_set
    from rheolin.results.dataset import point_dataset

    model = load_model(example_path("gearbox"))
    rows, qs = [], []
    t = time.perf_counter()
    template = model.speed_template() if hasattr(model, "speed_template") else None
    setup = time.perf_counter() - t
    assemble = template.assemble if template is not None else model.assemble
    previous = None
    base = status_kb("VmRSS")
    reset_peak()
    for rpm in RPMS:
        t0 = time.perf_counter()
        a = assemble(rpm * np.pi / 30)
        hset = harmonic_set(a, 3, 200)
        t1 = time.perf_counter()
        warm = {} if template is None or previous is None else {"x0": previous}
        sol = rl.solve(a.system, hset, stability=False, **warm)
        t2 = time.perf_counter()
        point_dataset(OperatingPoint(a, hset, sol, t2 - t0))
        t3 = time.perf_counter()
        previous = sol
        backend = sol.info.get("backend", "lu")
        rows.append(dict(rpm=rpm, assemble=t1 - t0, solve=t2 - t1, outputs=t3 - t2,
                         iterations=sol.iterations, residual=sol.residual,
                         success=bool(sol.success), backend=backend))  # fmt: skip
        qs.append(sol.q)
    np.save(out, np.array(qs))
    return dict(rows=rows, setup=setup, peak_mb=(status_kb("VmHWM") - base) / 1024)


def _sweep() -> dict:
    """``rheolin.results.sweep_speeds`` (what ``rheolin sweep`` runs per speed)."""
    from rheolin.data import example_path
    from rheolin.io import load_model
    from rheolin.results.sweep import sweep_speeds

    model = load_model(example_path("gearbox"))
    t = time.perf_counter()
    ds = sweep_speeds(model, np.array(RPMS) * np.pi / 30, order=3, max_order=200)
    assert ds["success"].values.all()
    return dict(per_speed=(time.perf_counter() - t) / len(RPMS))


def _ross_rotor() -> tuple:
    """ROSS's ``rotor_example`` (ross/rotor_assembly.py) and the same rotor in rheolin."""
    from rheolin.mechanics import Model

    E, G, rho = 211e9, 81.2e9, 7810.0  # ross.materials.steel
    m = Model()
    m.add_shaft("rotor", np.arange(7) * 0.25, outer_diameter=0.05, elastic_modulus=E,
                poisson_ratio=E / (2 * G) - 1, density=rho)  # fmt: skip
    for node in (2, 4):
        m.add_disk("rotor", node, outer_diameter=0.28, width=0.07, inner_diameter=0.05, density=rho)
    for name, node in (("b0", 0), ("b1", 6)):
        m.add_bearing(name, "rotor", node, [1e6, 0.8e6], 0.0)
    return m, 2, 1e-3  # model, unbalance node, unbalance [kg m]


def _ross(kind: str, n_speeds: int, out: str) -> dict:
    import warnings

    warnings.filterwarnings("ignore")
    import rheolin as rl
    from rheolin.results.speeds import lti_speeds

    speeds = np.linspace(*ROSS_RANGE, n_speeds)
    model, node, U = _ross_rotor()
    base = status_kb("VmRSS")  # after the imports: the memory the computation needs
    if kind == "ross":
        import ross as rs

        base = status_kb("VmRSS")
        reset_peak()
        t = time.perf_counter()
        rotor = rs.rotor_example()
        res = rotor.run_unbalance_response(node, U, 0.0, speeds)
        seconds = time.perf_counter() - t
        X = np.asarray(res.forced_resp).T  # (speeds, dof): one-sided amplitudes
    else:
        reset_peak()
        t = time.perf_counter()
        template = model.speed_template()
        ux = 6 * node

        def unbalance(w1: np.ndarray, n: int) -> np.ndarray:
            f = np.zeros((w1.size, template.n_dof), dtype=complex)
            f[:, ux], f[:, ux + 1] = U * w1**2 / 2, -0.5j * U * w1**2
            return f

        if kind == "batched":
            res = lti_speeds(template, speeds, [1], loads=unbalance)
            assert res.success.all()
            X = 2 * res.q[:, 0]
        else:  # the general API, one speed at a time
            X = np.empty((speeds.size, template.n_dof), dtype=complex)
            for i, W in enumerate(speeds):
                a = template.assemble(W)
                s = a.system
                system = rl.PeriodicSystem(a.omega, M=s.M, D=s.D, K=s.K,
                                           f={1: unbalance(np.array([a.omega]), 1)[0]})  # fmt: skip
                sol = rl.solve(system, [1], method="lti", stability=False)
                assert sol.success
                X[i] = 2 * sol.harmonic(1)
        seconds = time.perf_counter() - t
    np.save(out, X)
    return dict(seconds=seconds, peak_mb=(status_kb("VmHWM") - base) / 1024)


def _rss(n_solves: int) -> dict:
    sys.path.insert(0, str(HERE))
    import rheolin as rl
    from solvers import beam_system

    system = beam_system(1000)
    H = rl.HarmonicSet.full(25)
    marks = {}
    t = time.perf_counter()
    for i in range(n_solves):
        sol = rl.solve(system, H, method="gmres", stability=False)
        assert sol.success
        if i + 1 in (10, 100, n_solves):
            marks[i + 1] = status_kb("VmRSS") / 1024
    return dict(growth_mb=marks[n_solves] - marks[10], late_mb=marks[n_solves] - marks[100],
                rss_mb=marks[n_solves], seconds=time.perf_counter() - t)  # fmt: skip


def worker(args: list[str]) -> None:
    task, out = args[0], args[1]
    if task == "gearbox":
        result = _gearbox(out)
    elif task == "sweep":
        result = _sweep()
    elif task in ("ross", "batched", "loop"):
        result = _ross(task, int(args[2]), out)
    else:
        result = _rss(int(args[2]))
    print(json.dumps(result))


# --------------------------------------------------------------------------- driver
def run(task: str, src: Path, *extra: str, timeout: float = 3600) -> tuple[dict, np.ndarray | None]:
    out = tempfile.mktemp(suffix=".npy")
    env = dict(os.environ, PYTHONPATH=str(src))
    cmd = [sys.executable, __file__, "--worker", task, out, *extra]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    if proc.returncode:
        raise RuntimeError(f"{task} ({src}) failed:\n{proc.stderr[-3000:]}")
    data = np.load(out) if os.path.exists(out) else None
    if data is not None:
        os.unlink(out)
    return json.loads(proc.stdout.strip().splitlines()[-1]), data


def before_tree(path: str | None) -> Path:
    if path:
        return Path(path) / "src"
    dest = Path(tempfile.mkdtemp(prefix="rheolin-before-"))
    archive = subprocess.run(["git", "archive", BEFORE_COMMIT], cwd=HERE, capture_output=True)
    subprocess.run(["tar", "-x", "-C", str(dest)], input=archive.stdout, check=True)
    return dest / "src"


def _median(rows: list[dict], key: str, skip_first: bool = False) -> float:
    return float(np.median([r[key] for r in (rows[1:] if skip_first else rows)]))


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        worker(sys.argv[2:])
        return
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--before", help="source tree of the code before (default: git archive)")
    p.add_argument("--out", help="write the Markdown report here")
    p.add_argument("--ross-speeds", type=int, default=1000)
    p.add_argument("--rss-solves", type=int, default=500)
    p.add_argument("--skip-rss", action="store_true")
    args = p.parse_args()
    old, new = before_tree(args.before), HERE.parent / "src"
    lines = [
        "# Per-speed cost: before (1724902) / after, and ROSS 2.3",
        "",
        f"`OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}`, "
        f"{os.cpu_count()} CPUs; each measurement in its own process.",
        "",
        "## (a) Embedded gearbox, 126 DOF, 2,945 harmonics, per speed (median of "
        f"{len(RPMS)} speeds {RPMS[0]:g}-{RPMS[-1]:g} rpm)",
        "",
        "| | assembly [s] | solve [s] | outputs [s] | total [s] | gmres its | peak MB |",
        "|---|---|---|---|---|---|---|",
    ]
    res = {}
    for name, src in (("before", old), ("after", new)):
        res[name], q = run("gearbox", src)
        res[name]["q"] = q
        rows = res[name]["rows"]
        tot = [r["assemble"] + r["solve"] + r["outputs"] for r in rows]
        res[name]["total"] = float(np.median(tot))
        its = "/".join(str(r["iterations"]) for r in rows)
        lines.append(
            f"| {name} | {_median(rows, 'assemble'):.4f} | {_median(rows, 'solve'):.3f} | "
            f"{_median(rows, 'outputs'):.4f} | {res[name]['total']:.3f} | {its} | "
            f"{res[name]['peak_mb']:.0f} |"
        )
        print(lines[-1], flush=True)
    b, a = res["before"], res["after"]
    parts = ("assemble", "solve", "outputs")
    ratio = {k: _median(b["rows"], k) / _median(a["rows"], k) for k in parts}
    qa, qb = a["q"], b["q"]
    agree = float(np.max(np.abs(qa - qb)) / np.max(np.abs(qb)))
    lines += [
        f"| before / after | {ratio['assemble']:.1f}x | {ratio['solve']:.1f}x | "
        f"{ratio['outputs']:.0f}x | **{b['total'] / a['total']:.1f}x** | | |",
        "",
        f"Largest difference of the answers (all harmonics, DOFs, speeds) / largest value: "
        f"{agree:.1e}; residuals after: "
        f"{max(r['residual'] for r in a['rows']):.1e} (all success: "
        f"{all(r['success'] for r in a['rows'])}); backend after: {a['rows'][0]['backend']}. "
        f"Template made once: {a['setup']:.3f} s.",
        "",
    ]
    assert agree < 1e-9, agree
    sweep = {
        name: run("sweep", src)[0]["per_speed"] for name, src in (("before", old), ("after", new))
    }
    lines += [
        f"`rheolin.results.sweep_speeds` (what `rheolin sweep` runs), same speeds: "
        f"{sweep['before']:.2f} s -> {sweep['after']:.2f} s per speed "
        f"({sweep['before'] / sweep['after']:.1f}x).",
        "",
    ]
    n = args.ross_speeds
    lines += [
        f"## (b) ROSS `rotor_example` (42 DOF), unbalance response at {n} speeds",
        "",
        "| | seconds | per speed [ms] | peak MB (above imports) | ROSS / this |",
        "|---|---|---|---|---|",
    ]
    ross, X_ross = run("ross", new, str(n))
    out = {"ross": (ross, X_ross)}
    for kind in ("batched", "loop"):
        out[kind] = run(kind, new, str(n))
    for kind, label in (("ross", "ROSS 2.3 `run_unbalance_response`"),
                        ("batched", "rheolin `lti_speeds` (batched)"),
                        ("loop", "rheolin loop: `template.assemble` + `rl.solve`")):  # fmt: skip
        r, X = out[kind]
        lines.append(
            f"| {label} | {r['seconds']:.3f} | {1e3 * r['seconds'] / n:.3f} | "
            f"{r['peak_mb']:.1f} | {ross['seconds'] / r['seconds']:.1f}x time, "
            f"{ross['peak_mb'] / max(r['peak_mb'], 0.1):.1f}x memory |"
        )
        print(lines[-1], flush=True)
    xy = [6 * k + j for k in range(7) for j in (0, 1)]
    errs = {}
    for kind in ("batched", "loop"):
        X = out[kind][1]
        assert X_ross is not None and X is not None
        diff = np.abs(X[:, xy] - X_ross[:, xy]).max(axis=1) / np.abs(X_ross[:, xy]).max(axis=1)
        errs[kind] = float(diff.max())
    lines += [
        "",
        f"Agreement with ROSS (translations of every node, largest over speeds, relative to "
        f"the largest response at that speed): batched {errs['batched']:.1e}, loop "
        f"{errs['loop']:.1e}.",
        "",
    ]
    assert max(errs.values()) < 1e-9, errs
    if not args.skip_rss:
        lines += [
            f"## (c) Resident memory over {args.rss_solves} `rl.solve` calls (1000-DOF chain, "
            "51 harmonics, gmres, default workers)",
            "",
            "| | RSS growth 10 -> N solves [MB] | 100 -> N [MB] | RSS at the end [MB] | seconds |",
            "|---|---|---|---|---|",
        ]
        for name, src in (("before", old), ("after", new)):
            r, _ = run("rss", src, str(args.rss_solves))
            lines.append(
                f"| {name} | {r['growth_mb']:.0f} | {r['late_mb']:.0f} | {r['rss_mb']:.0f} | "
                f"{r['seconds']:.1f} |"
            )
            print(lines[-1], flush=True)
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        Path(args.out).write_text(text)


if __name__ == "__main__":
    main()
