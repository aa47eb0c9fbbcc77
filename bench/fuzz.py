"""Long fuzzing run of the whole surface (the strategies of tests/reliability/fuzz_*.py).

    OPENBLAS_NUM_THREADS=1 python bench/fuzz.py --models 10000 --arguments 2000 \
        --surface 3000 --api 3000 --semantic 1000 --out bench/results/fuzz.md

Categories: mutated model files (``validate``, and ``draw`` of those valid), hostile ``run``
command lines, the other commands (``frf``, ``modes``, ``campbell``, ``critical-map``,
``sweep --vary``, ``condense`` specs, ``import-ross`` files, ``draw``, ``report`` of result
directories real and hostile, ``RHEOLIN_*`` variables), the Python entry points (``rl.solve``,
``rl.floquet``, ``Model.add_*``) and semantic mutations (duplicates that add or are refused,
impossible physics). Counts each outcome and every contract violation: exit 3, a traceback,
an error line without a field, an API exception of another type or naming nothing, a
semantic promise broken, and a case using more than ``--hang`` CPU seconds (a hang: CPU
time, so that a machine shared with other work does not count as one). Reports the
slowest case per category (CPU seconds), the peak resident memory, and a size scenario
(the assembly memory per shaft element, which the load-time size check assumes).
"""

from __future__ import annotations

import argparse
import gc
import os
import resource
import sys
import tempfile
import time
from collections import Counter, defaultdict
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, given, settings
from typer.testing import CliRunner

sys.path.insert(0, str(Path(__file__).parents[1] / "tests" / "reliability"))
from fuzz_cases import check_outcome, mutated_model, run_arguments
from fuzz_semantic import check_semantic, semantic_case
from fuzz_surface import (
    api_case,
    check_call,
    cli_case,
    condense_spec,
    ross_text,
    write_fe,
    write_results,
)

from rheolin.cli import app
from rheolin.data import example_text


class Tally:
    """Outcomes, violations and the slowest case of each category."""

    def __init__(self, hang: float) -> None:
        self.hang = hang
        self.counts: dict[str, Counter] = defaultdict(Counter)
        self.slowest: dict[str, tuple[float, str]] = defaultdict(lambda: (0.0, ""))
        self.violations: list[str] = []

    def record(self, kind: str, judge: Any, case: str, seconds: float) -> None:
        try:
            outcome = judge()
            if seconds > self.hang:
                raise AssertionError(f"took {seconds:.1f} CPU s (a hang: over {self.hang:g} s)")
            self.counts[kind][outcome] += 1
        except AssertionError as exc:
            self.counts[kind]["VIOLATION"] += 1
            self.violations.append(f"{kind}: {exc!s:.400} | case: {case[:400]!r}")
            print(f"VIOLATION {self.violations[-1]}", file=sys.stderr, flush=True)
        done = sum(sum(c.values()) for c in self.counts.values())
        if done % 500 == 0:  # a log to follow a long run, and to read if it is stopped
            print(f"{done} cases, {time.process_time():.0f} CPU s", file=sys.stderr, flush=True)
        if seconds > self.slowest[kind][0]:
            self.slowest[kind] = (seconds, case[:200])


def element_memory() -> tuple[float, float]:
    """Memory per shaft element of an assembled model [bytes]: kept, and at the peak of the
    assembly (tracemalloc, which sees NumPy's arrays; the rotor example at 1,000 and 4,000
    nodes, the difference divided by the elements added)."""
    import tracemalloc

    from rheolin.io import parse_model

    kept, peak = [], []
    for n in (1000, 4000):
        positions = " ".join(f"{600 * i / (n - 1):.6f}" for i in range(n))
        text = example_text("rotor").replace('"0 300 600 mm"', f'"{positions} mm"')
        lm = parse_model(text.replace("node = 2\n", f"node = {n - 1}\n"))
        gc.collect()
        tracemalloc.start()
        assembled = lm.model.assemble(300.0)
        now, top = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        kept.append(now)
        peak.append(top)
        del assembled, lm
        gc.collect()
    return (kept[1] - kept[0]) / 3000, (peak[1] - peak[0]) / 3000


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    for name, default in (("models", 10000), ("arguments", 2000), ("surface", 3000),
                          ("api", 3000), ("semantic", 1000)):  # fmt: skip
        ap.add_argument(f"--{name}", type=int, default=default)
    ap.add_argument(
        "--hang", type=float, default=60.0, help="A case using more CPU seconds than this hangs."
    )
    ap.add_argument("--out", type=Path, default=None)
    a = ap.parse_args()
    os.environ.setdefault("RHEOLIN_SOLVE_MEMORY", "256 MB")
    os.environ.setdefault("RHEOLIN_MEMORY_BUDGET", "256 MB")
    runner = CliRunner()
    tmp = Path(tempfile.mkdtemp(prefix="rheolin-fuzz-"))
    (tmp / "file").write_text("not a directory")
    os.chdir(tmp)  # `--out ''` is the working directory
    model = tmp / "rotor.toml"
    model.write_text(example_text("rotor"))
    write_fe(tmp)
    write_results(tmp / "res")
    tally = Tally(a.hang)
    common: dict[str, Any] = dict(
        deadline=None, database=None, derandomize=True, suppress_health_check=list(HealthCheck)
    )

    def invoke(args: list[str], env: dict[str, str] | None = None) -> Any:
        return runner.invoke(app, args, catch_exceptions=False, env=env)

    def cli(kind: str, args: list[str], env: dict[str, str] | None, case: str) -> str:
        t0 = time.process_time()
        res = invoke(args, env)
        seconds = time.process_time() - t0
        tally.record(kind, lambda: check_outcome(res.exit_code, res.stdout, res.stderr), case,
                     seconds)  # fmt: skip
        return {0: "ok", 1: "failed", 2: "refused"}.get(res.exit_code, "")

    # a result directory of each kind the report reads fully (the others are hostile)
    for argv in (["run", str(model), "--out", str(tmp / "res" / "run")],
                 ["campbell", str(model), "--speeds", "0:6000:1000rpm", "--out",
                  str(tmp / "res" / "run")]):  # fmt: skip
        assert invoke(argv).exit_code == 0, argv

    @settings(max_examples=max(a.models, 1), **common)
    @given(text=mutated_model())
    def models(text: str) -> None:
        path = tmp / "m.toml"
        path.write_text(text)
        if cli("models (validate)", ["validate", str(path)], None, text) == "ok":
            cli("models (draw)", ["draw", str(path), "--out", str(tmp / "m.png")], None, text)

    @settings(max_examples=max(a.arguments, 1), **common)
    @given(args=run_arguments())
    def arguments(args: list[str]) -> None:
        cli("run arguments", [x.format(model=model, tmp=tmp) for x in args], None, " ".join(args))

    @settings(max_examples=max(a.surface, 1), **common)
    @given(case=cli_case(), spec=condense_spec(), ross=ross_text())
    def surface(case: tuple[str, list[str], dict[str, str]], spec: str, ross: str) -> None:
        kind, args, env = case
        (tmp / "spec.toml").write_text(spec)
        (tmp / "r.toml").write_text(ross)
        files = dict(model=str(model), spec=str(tmp / "spec.toml"), ross=str(tmp / "r.toml"),
                     res=str(tmp / "res"))  # fmt: skip
        argv = [x.format(tmp=tmp, **files) for x in args]
        shown = " ".join(args) + (f" env {env}" if env else "")
        shown += {"condense": f" | spec: {spec}", "ross": f" | rotor: {ross}"}.get(kind, "")
        cli(kind, argv, env, shown)

    @settings(max_examples=max(a.api, 1), **common)
    @given(case=api_case())
    def api(case: Any) -> None:
        label, call, names = case
        t0 = time.process_time()
        judge = lambda: check_call(call, names)  # noqa: E731
        outcome: list[str] = []
        try:
            outcome.append(judge())
            error: AssertionError | None = None
        except AssertionError as exc:
            error = exc
        seconds = time.process_time() - t0

        def replay() -> str:
            if error is not None:
                raise error
            return outcome[0]

        tally.record("Python entry points", replay, label, seconds)

    @settings(max_examples=max(a.semantic, 1), **common)
    @given(case=semantic_case())
    def semantic(case: Any) -> None:
        t0 = time.process_time()
        try:
            outcome = check_semantic(case)
            error = None
        except Exception as exc:
            outcome, error = "", exc
        seconds = time.process_time() - t0

        def replay() -> str:
            if error is not None:
                raise AssertionError(f"{type(error).__name__}: {error}")
            return outcome

        tally.record("semantic mutations", replay, case[0], seconds)

    t0 = time.perf_counter()
    timing = {}
    stopped = ""
    for name, fn, n in (("models", models, a.models), ("arguments", arguments, a.arguments),
                        ("surface", surface, a.surface), ("api", api, a.api),
                        ("semantic", semantic, a.semantic)):  # fmt: skip
        if n and not stopped:
            t = time.perf_counter()
            try:
                fn()
            except KeyboardInterrupt:  # a deadline (timeout -s INT): report what ran
                stopped = f"Stopped by SIGINT during the {name} part; the counts are the cases run."
            timing[name] = time.perf_counter() - t
    total = time.perf_counter() - t0
    cpu = time.process_time()
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    per_element = element_memory()
    run = sum(sum(c.values()) for c in tally.counts.values())
    lines = [
        "# Fuzzing the whole surface (bench/fuzz.py)",
        "",
        f"`python bench/fuzz.py --models {a.models} --arguments {a.arguments} --surface "
        f"{a.surface} --api {a.api} --semantic {a.semantic}`: {run} cases in {total:.0f} s "
        f"({cpu:.0f} CPU s), "
        f"peak RSS {rss:.0f} MB, hang threshold {a.hang:g} s (RHEOLIN_SOLVE_MEMORY and "
        "RHEOLIN_MEMORY_BUDGET 256 MB unless a case sets them)",
        "",
        "| category | cases | ok (exit 0 / result / adds) | refused, field named (exit 2 / "
        "exception) | honest failure (exit 1) | contract violations | slowest case [CPU s] |",
        "|---|---|---|---|---|---|---|",
    ]
    for kind in sorted(tally.counts):
        c = tally.counts[kind]
        ok = c["ok"] + c["adds"]
        lines.append(
            f"| {kind} | {sum(c.values())} | {ok} | {c['refused']} | {c['failed']} | "
            f"{c['VIOLATION']} | {tally.slowest[kind][0]:.2f} |"
        )
    lines += [
        "",
        "Wall time per part: " + ", ".join(f"{k} {v:.0f} s" for k, v in timing.items()) + ".",
        *(["", stopped] if stopped else []),
        "",
        f"Memory per shaft element of an assembled model (tracemalloc; the rotor example at "
        f"1,000 and 4,000 nodes): {per_element[0] / 1e3:.1f} kB kept, {per_element[1] / 1e3:.1f} "
        "kB at the peak of the assembly (the load-time size check assumes 64 kB).",
        "",
        "Slowest case of each category (CPU seconds):",
        "",
        *[
            f"- {k}: {v[0]:.2f} s: `{' / '.join(v[1][:160].splitlines())}`"
            for k, v in sorted(tally.slowest.items())
        ],
        "",
        f"Violations ({len(tally.violations)}):" if tally.violations else "No violation.",
        "",
        *[f"- {v}" for v in tally.violations[:40]],
    ]
    text = "\n".join(lines) + "\n"
    print(text)
    if a.out:
        a.out.parent.mkdir(parents=True, exist_ok=True)
        a.out.write_text(text)


if __name__ == "__main__":
    main()
