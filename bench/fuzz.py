"""Long fuzzing run of the CLI (the strategies of tests/reliability/fuzz_cases.py).

    OPENBLAS_NUM_THREADS=1 python bench/fuzz.py --models 10000 --arguments 2000 \
        --out bench/results/fuzz.md

Counts each outcome (valid, refused with exit 2 naming a field, honest failure exit 1) and
every contract violation (exit 3, a traceback, an error line without a field), with the
slowest case and the peak resident memory of the process.
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from typer.testing import CliRunner

sys.path.insert(0, str(Path(__file__).parents[1] / "tests" / "reliability"))
from fuzz_cases import check_outcome, mutated_model, run_arguments

from rheolin.cli import app
from rheolin.data import example_text


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--models", type=int, default=10000)
    ap.add_argument("--arguments", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
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
    counts: dict[str, Counter] = {"models": Counter(), "arguments": Counter()}
    slowest = {"models": (0.0, ""), "arguments": (0.0, "")}
    violations: list[str] = []

    def record(kind: str, res, case: str, seconds: float) -> None:
        try:
            counts[kind][check_outcome(res.exit_code, res.stdout, res.stderr)] += 1
        except AssertionError as exc:
            counts[kind]["VIOLATION"] += 1
            violations.append(f"{kind}: {exc!s:.400} | case: {case[:400]!r}")
        if seconds > slowest[kind][0]:
            slowest[kind] = (seconds, case[:200])

    common = dict(
        deadline=None,
        database=None,
        suppress_health_check=list(HealthCheck),
    )

    @settings(max_examples=a.models, **common)
    @given(text=mutated_model())
    def models(text: str) -> None:
        path = tmp / "m.toml"
        path.write_text(text)
        t0 = time.perf_counter()
        res = runner.invoke(app, ["validate", str(path)], catch_exceptions=False)
        record("models", res, text, time.perf_counter() - t0)

    @settings(max_examples=a.arguments, **common)
    @given(args=run_arguments())
    def arguments(args: list[str]) -> None:
        argv = [x.format(model=model, tmp=tmp) for x in args]
        t0 = time.perf_counter()
        res = runner.invoke(app, argv, catch_exceptions=False)
        record("arguments", res, " ".join(args), time.perf_counter() - t0)

    t0 = time.perf_counter()
    if a.models:
        models()
    if a.arguments:
        arguments()
    total = time.perf_counter() - t0
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    lines = [
        "# Fuzzing the CLI (bench/fuzz.py)",
        "",
        f"`python bench/fuzz.py --models {a.models} --arguments {a.arguments}`, "
        f"{total:.0f} s, peak RSS {rss:.0f} MB",
        "",
        "| cases | run | valid (exit 0) | refused, field named (exit 2) | honest failure (exit 1) "
        "| contract violations | slowest case [s] |",
        "|---|---|---|---|---|---|---|",
    ]
    for kind in ("models", "arguments"):
        c = counts[kind]
        lines.append(
            f"| {kind} | {sum(c.values())} | {c['ok']} | {c['refused']} | {c['failed']} | "
            f"{c['VIOLATION']} | {slowest[kind][0]:.2f} |"
        )
    lines += ["", *[f"- {v}" for v in violations[:20]]]
    text = "\n".join(lines) + "\n"
    print(text)
    if a.out:
        a.out.parent.mkdir(parents=True, exist_ok=True)
        a.out.write_text(text)


if __name__ == "__main__":
    main()
