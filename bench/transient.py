"""Transient BDF baseline against the frequency domain, same model, one run (not a test).

Models (the embedded example of ``rheolin.data``, at 3000 rpm):

* ``variant``: the two-stage gearbox with non-hunting tooth counts 20:70 and 18:72 (same
  centre distances, modules, shafts, bearings, unbalance), so ``w1`` = input / 14 and the
  response repeats every 14 input revolutions (0.28 s): the transient can run to its periodic
  steady state.
* ``gearbox``: the example as shipped, hunting-tooth 23:67 / 19:71, ``w1`` = input / 4757: the
  response repeats only every 4757 input revolutions (95 s). The detector needs two such
  periods; each backend integrates ``PROBE`` seconds of simulated time at the ``rtol`` it
  needed on the variant, and its wall time is extrapolated to ``2 x 95 s`` from the rate of
  the probe's second half (marked "est."): a lower bound, since the detector could need a
  third period.

Every method runs in a fresh subprocess (peak resident memory = VmHWM, including SuperLU's
C allocations). Accuracy: relative error of the dominant harmonics (those with an amplitude of
at least 1 % of the largest) against ``gmres`` at ``rtol = 1e-12`` on a wider harmonic set
(closure order 4 and max_order 250 instead of the file's 3 and 200); each method must reach
1e-4. The transient stops when the change between consecutive periods is below that same
target (``period_tol = 1e-4``) and tries ``rtol`` = 1e-6, 1e-7 in turn, reporting the first
that reaches it. (At ``rtol = 1e-5`` the change between periods of the variant sits at
1.4-1.7e-4, the integrator's own noise, from the third period on: it cannot stop at 1e-4.)
The frequency-domain methods likewise try the harmonic set of closure order 2, then the
file's order 3 (both at the file's cut-off), reporting the first that reaches 1e-4: the
harmonic set is their discretization, as the step-size tolerance is the transient's.
Each transient run (and probe) gets ``--transient-timeout`` seconds; a run that hits it is
reported with that time as a lower bound (">").

``direct`` gets ``--direct-timeout`` seconds (the coupled LU of these models fills far beyond
the per-harmonic factors; "where it fits").

Usage::

    python bench/transient.py [--out bench/results/transient.md] [--timeout 3600]
                              [--direct-timeout 300] [--transient-timeout 600]
                              [--models variant,gearbox]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from _memory import reset_peak, status_kb

SPEED = 2 * math.pi * 50.0  # 3000 rpm [rad/s]
ACCURACY = 1e-4
#: Simulated time [s] of the transient probe on the hunting-tooth gearbox.
PROBE = 0.5
FD_METHODS = ("perturbation", "gmres", "direct")
TRANSIENT_RTOLS = (1e-6, 1e-7)
#: Harmonic sets tried by the frequency-domain methods, cheapest first (closure order at the
#: file's cut-off; 0 = the file's own order 3): the counterpart of the transient's rtol ladder.
FD_ORDERS = (2, 0)


def model_text(name: str) -> str:
    from rheolin.data import example_text

    text = example_text("gearbox")
    if name == "variant":
        for old, new in (
            ("pinion_teeth = 23", "pinion_teeth = 20"),
            ("gear_teeth = 67", "gear_teeth = 70"),
            ("pinion_teeth = 19", "pinion_teeth = 18"),
            ("gear_teeth = 71", "gear_teeth = 72"),
        ):
            assert old in text, old
            text = text.replace(old, new)
    return text


def setup(name: str, reference: bool = False, order: int = 0):  # type: ignore[no-untyped-def]
    """System and harmonic set: the model file's ``[harmonics]`` (order 3, max_order 200) or
    closure order ``order`` (if > 0) at the file's cut-off; for the reference one closure
    order more than the file and a 25 % higher cut-off."""
    from rheolin.io.loader import parse_model
    from rheolin.results.compute import harmonic_set

    lm = parse_model(model_text(name))
    file_order, max_order = lm.spec.harmonics.order, lm.spec.harmonics.max_order
    assert max_order is not None
    a = lm.model.assemble(SPEED)
    if reference:
        return a, harmonic_set(a, file_order + 1, 1.25 * max_order)
    return a, harmonic_set(a, order if order > 0 else file_order, max_order)


# --------------------------------------------------------------------------- measurement
def worker(model: str, method: str, rtol: float, backend: str, out: str, order: int) -> None:
    """One method in this fresh process: time, peak memory, harmonics."""
    import rheolin as rl
    import rheolin.solvers.transient

    a, H = setup(model, reference=method == "reference", order=order)
    base = status_kb("VmRSS")
    reset_peak()
    t0 = time.perf_counter()
    info: dict = {}
    if method == "probe":
        info = probe(a.system, H, rtol, backend)
    else:
        m = "gmres" if method == "reference" else method
        opts = (
            {"backend": backend, "rtol": rtol, "period_tol": ACCURACY} if m == "transient" else None
        )
        sol = rl.solve(
            a.system,
            H,
            method=m,
            rtol=1e-12 if method == "reference" else 1e-8,
            stability=False,
            options=opts,
        )
        np.save(out + ".npy", sol.q)
        np.save(out + ".h.npy", sol.harmonics)
        info = {
            "success": sol.success,
            "message": sol.message[:200],
            "iterations": sol.iterations,
            "steps": sol.info.get("steps", 0),
        }
    info["seconds"] = time.perf_counter() - t0
    info["peak_mb"] = status_kb("VmHWM") / 1024
    info["extra_mb"] = (status_kb("VmHWM") - base) / 1024
    Path(out + ".json").write_text(json.dumps(info))


class _Probe:
    """Stands in for the steady-state detector of the transient backends: ends the run at
    ``end`` s of simulated time and times its second half (past the start from rest)."""

    def __init__(self, end: float) -> None:
        self.end, self.done, self.periods, self.steps = end, False, 0, 0
        self.t_half = self.t_end = 0.0
        self.steps_half = 0

    def take(self, q: np.ndarray) -> None:
        pass

    def pending(self, t: float) -> np.ndarray:  # called once per integrator step
        self.steps += 1
        if not self.t_half and t >= self.end / 2:
            self.t_half, self.steps_half = time.perf_counter(), self.steps
        if t >= self.end:
            self.done, self.t_end = True, time.perf_counter()
        return np.zeros(0)


def probe(system, H, rtol: float, backend: str) -> dict:  # type: ignore[no-untyped-def]
    """Integrate ``PROBE`` s with the transient backend itself; extrapolate to 2 periods.

    Estimate = wall time of the first half (the start) + the second half's rate over the
    rest of two periods: a lower bound (the detector needs at least two periods).
    """
    import rheolin.solvers.transient as tr
    from rheolin.harmonics.balance import HarmonicBalance
    from rheolin.solvers.registry import Options
    from rheolin.solvers.transient.backends import run_scipy, run_sundae
    from rheolin.solvers.transient.model import Coefficients

    op = HarmonicBalance(system, H)
    s = tr.TransientSettings.from_options(op, Options(extra={"rtol": rtol, "backend": backend}))
    det = _Probe(PROBE)
    t0 = time.perf_counter()
    run = run_sundae if backend == "sundae" else run_scipy
    stats = run(Coefficients(system), s, det)  # type: ignore[arg-type]
    if "failed" in stats or not det.done:
        return {"error": stats.get("failed", "probe did not reach its end")}
    needed = 2 * s.period  # the detector's minimum: two full periods
    rate = (det.t_end - det.t_half) / (PROBE / 2)  # wall seconds per simulated second
    step_rate = (det.steps - det.steps_half) / (PROBE / 2)
    return {
        "success": True,
        "probe_steps": det.steps,
        "probe_wall": det.t_end - t0,
        "needed_time": needed,
        "est_seconds": (det.t_half - t0) + rate * (needed - PROBE / 2),
        "est_steps": int(det.steps_half + step_rate * (needed - PROBE / 2)),
        "samples": s.samples,
        "sample_buffer_mb": 2 * s.samples * system.n * 8 / 2**20,
        "period": s.period,
    }


def measure(
    model: str,
    method: str,
    tmp: str,
    timeout: float,
    rtol: float = 0.0,
    backend: str = "scipy",
    order: int = 0,
) -> dict:
    out = os.path.join(tmp, f"{model}_{method}_{backend}_{rtol:g}_{order}")
    args = [model, method, repr(rtol), backend, out, str(order)]
    cmd = [sys.executable, __file__, "--worker", *args]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"error": f"timeout after {timeout:.0f} s"}
    if proc.returncode != 0:
        tail = (proc.stderr or "").strip().splitlines()[-1:] or [f"exit {proc.returncode}"]
        return {"error": tail[0][:120]}
    info = json.loads(Path(out + ".json").read_text())
    if Path(out + ".npy").exists():
        info["q"], info["h"] = np.load(out + ".npy"), np.load(out + ".h.npy")
    return info


def dominant_error(q: np.ndarray, h: np.ndarray, ref_q: np.ndarray, ref_h: np.ndarray) -> float:
    """Max over the dominant harmonics of ``|q_n - ref_n|_inf / |ref_n|_inf``."""
    amp = np.abs(ref_q).max(axis=1)
    where = {int(k): i for i, k in enumerate(ref_h)}
    errs = []
    for j, n in enumerate(h):
        i = where.get(int(n))
        if i is not None and amp[i] >= 0.01 * amp.max():
            errs.append(np.abs(q[j] - ref_q[i]).max() / amp[i])
    return float(max(errs))


# --------------------------------------------------------------------------- the table
def run(
    out: Path, timeout: float, direct_timeout: float, transient_timeout: float, models: list[str]
) -> str:
    import rheolin.solvers.transient as tr

    backends = ["scipy"] + (["sundae"] if tr.sundae_available() else [])
    lines = [
        "# Transient (BDF) vs frequency domain",
        "",
        f"Command: `python bench/transient.py --out {out} --timeout {timeout:g} "
        f"--direct-timeout {direct_timeout:g} --transient-timeout {transient_timeout:g} "
        f"--models {','.join(models)}`  ",
        f"Machine: {os.cpu_count()} cores; accuracy target {ACCURACY:g} on the dominant "
        "harmonics against gmres (rtol 1e-12) on a wider harmonic set (closure order 4, "
        "max_order 250). The frequency-domain methods try closure order 2, then the file's "
        "order 3 (max_order 200); the transient tries rtol 1e-6, then 1e-7. Each row reports "
        "the first that reaches the target.",
        "",
    ]
    accepted: dict[str, float] = {}  # backend -> the rtol that reached the accuracy
    with tempfile.TemporaryDirectory() as tmp:
        for model in models:
            a, H = setup(model)
            ref = measure(model, "reference", tmp, timeout)
            head = (
                f"## {model}: {a.system.n} DOF, w1 = {a.omega:.4g} rad/s (period "
                f"{2 * math.pi / a.omega:.4g} s), |H| = {len(H)}, max harmonic {max(H)}"
            )
            print(head, flush=True)
            lines += [
                head,
                "",
                "| method | seconds | peak MB | error | note |",
                "|---|---:|---:|---:|---|",
            ]
            rows: dict[str, float] = {}
            for m in FD_METHODS:
                fd_tried: list[str] = []
                for order in FD_ORDERS:
                    label = f"order {order}" if order else "the file's order"
                    r = measure(
                        model, m, tmp, direct_timeout if m == "direct" else timeout, order=order
                    )
                    if "error" in r:
                        fd_tried.append(f"{label}: {r['error']}")
                        lines.append(f"| {m} | — | — | — | {'; '.join(fd_tried)} |")
                        break  # a larger set would not fit either
                    err = dominant_error(r["q"], r["h"], ref["q"], ref["h"])
                    ok = r["success"] and err <= ACCURACY
                    if ok:
                        rows[m] = r["seconds"]
                        note = "; ".join(
                            [*fd_tried, f"{label}, {r['h'].size} harmonics: {r['iterations']} it"]
                        )
                        lines.append(
                            f"| {m} | {r['seconds']:.3f} | {r['peak_mb']:.0f} | {err:.1e} "
                            f"| {note} |"
                        )
                        break
                    fd_tried.append(
                        f"{label} ({r['h'].size} harmonics): error {err:.1e} "
                        f"in {r['seconds']:.2f} s"
                        + ("" if r["success"] else f" ({r['message'][:80]})")
                    )
                else:
                    lines.append(f"| {m} | — | — | — | {'; '.join(fd_tried)} |")
                print(lines[-1], flush=True)
            best = min(rows.values()) if rows else float("nan")
            bound: dict[str, str] = {}  # name -> why its time is only a lower bound
            for be in backends:
                name = f"transient ({be})"
                if model == "gearbox":
                    rt = accepted.get(be, TRANSIENT_RTOLS[0])
                    origin = (
                        "accepted on the variant"
                        if be in accepted
                        else "the first tried; it did not finish the variant"
                    )
                    r = measure(model, "probe", tmp, transient_timeout, rtol=rt, backend=be)
                    if "error" in r:
                        lines.append(f"| {name} | — | — | — | probe: {r['error']} |")
                        continue
                    lines.append(
                        f"| {name} | est. {r['est_seconds']:.3g} | "
                        f"≥ {r['sample_buffer_mb']:.0f} | — | rtol {rt:g} ({origin}); "
                        f"{r['probe_steps']} steps in {PROBE} s simulated "
                        f"({r['probe_wall']:.1f} s wall), extrapolated to 2 periods = "
                        f"{r['needed_time']:.1f} s simulated, ~{r['est_steps']:.2e} steps; "
                        f"memory = the detector's two-period sample buffer ({r['samples']} "
                        "samples) |"
                    )
                    rows[name] = r["est_seconds"]
                    bound[name] = " (est., a lower bound)"
                    print(lines[-1], flush=True)
                    continue
                tried: list[str] = []
                for rt in TRANSIENT_RTOLS:
                    r = measure(model, "transient", tmp, transient_timeout, rtol=rt, backend=be)
                    if "error" in r:
                        tried.append(f"rtol {rt:g}: {r['error']}")
                        timed_out = r["error"].startswith("timeout")
                        sec = f"> {transient_timeout:g}" if timed_out else "—"
                        lines.append(f"| {name} | {sec} | — | — | {'; '.join(tried)} |")
                        if timed_out:
                            rows[name] = transient_timeout
                            bound[name] = " (a lower bound: timed out)"
                        print(lines[-1], flush=True)
                        break
                    err = dominant_error(r["q"], r["h"], ref["q"], ref["h"])
                    print(f"  {name} rtol {rt:g}: {r['seconds']:.1f} s, err {err:.1e}", flush=True)
                    if r["success"] and err <= ACCURACY:
                        rows[name] = r["seconds"]
                        accepted[be] = rt
                        lines.append(
                            f"| {name} | {r['seconds']:.1f} | {r['peak_mb']:.0f} | {err:.1e} "
                            f"| {'; '.join([*tried, f'rtol {rt:g}'])}: {r['iterations']} "
                            f"periods, {r['steps']} steps |"
                        )
                        print(lines[-1], flush=True)
                        break
                    tried.append(
                        f"rtol {rt:g}: error {err:.1e} in {r['seconds']:.0f} s"
                        + ("" if r["success"] else f" ({r['message'][:80]})")
                    )
                else:
                    lines.append(f"| {name} | — | — | — | {'; '.join(tried)} |")
            lines.append("")
            for name, seconds in rows.items():
                if name.startswith("transient"):
                    for m in FD_METHODS:
                        if m in rows:
                            why = bound.get(name, "")
                            lines.append(f"* {name} / {m}: **{seconds / rows[m]:.0f}x**{why}")
            if rows and not math.isnan(best):
                lines.append(f"* fastest frequency-domain method: {best:.3f} s")
            lines.append("")
    return "\n".join(lines) + "\n"


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        model, method, rtol, backend, out, order = sys.argv[2:8]
        worker(model, method, float(rtol), backend, out, int(order))
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("bench/results/transient.md"))
    parser.add_argument("--timeout", type=float, default=3600.0)
    parser.add_argument("--direct-timeout", type=float, default=300.0)
    parser.add_argument("--transient-timeout", type=float, default=600.0)
    parser.add_argument("--models", default="variant,gearbox", help="variant, gearbox or both")
    args = parser.parse_args()
    text = run(
        args.out,
        args.timeout,
        args.direct_timeout,
        args.transient_timeout,
        args.models.split(","),
    )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
