"""Every single mutation of the preloaded example through its static equilibrium.

    OPENBLAS_NUM_THREADS=1 python bench/preload_scan.py

Each value of the example file is replaced by every hostile value of
tests/reliability/fuzz_cases.py, scaled by -1, 0, 1e-9, 1e3 and 1e12 (numbers), or deleted;
the files that load as a preloaded model are solved for their operating point at 1000 rpm
in-process. Counts the equilibria found, the refusals by their first words, and any error
that is not a refusal (``ModelError``) or a failure to converge ("static equilibrium not
found"). Memory is capped (``RLIMIT_AS`` 4 GB, budgets 256 MB) so that a size mutation fails
here rather than on the machine.
"""

from __future__ import annotations

import copy
import math
import os
import resource
import sys
import time
import tomllib
from collections import Counter
from pathlib import Path

import tomli_w

sys.path.insert(0, str(Path(__file__).parents[1] / "tests" / "reliability"))
from fuzz_cases import HOSTILE_VALUES, _get, _paths

from rheolin.data import example_text
from rheolin.errors import ModelError
from rheolin.io import parse_model

FACTORS = (-1.0, 0.0, 1e-9, 1e3, 1e12)


def mutations(doc: dict) -> list[tuple[tuple, str, object]]:
    """``(path, kind, argument)`` of every single mutation."""
    out = []
    for path in _paths(doc):
        value = _get(doc, path[:-1])[path[-1]]
        out.append((path, "delete", None))
        if isinstance(value, int | float) and not isinstance(value, bool):
            out += [(path, "scale", f) for f in FACTORS]
        out += [(path, "replace", h) for h in HOSTILE_VALUES]
    return out


def main() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (4 << 30, resource.getrlimit(resource.RLIMIT_AS)[1]))
    os.environ.setdefault("RHEOLIN_SOLVE_MEMORY", "256 MB")
    os.environ.setdefault("RHEOLIN_MEMORY_BUDGET", "256 MB")
    doc0 = tomllib.loads(example_text("preloaded"))
    outcomes: Counter = Counter()
    bad = []
    t0 = time.process_time()
    cases = mutations(doc0)
    for path, kind, arg in cases:
        doc = copy.deepcopy(doc0)
        parent = _get(doc, path[:-1])
        if kind == "delete":
            del parent[path[-1]]
        elif kind == "scale":
            parent[path[-1]] = parent[path[-1]] * arg
        else:
            parent[path[-1]] = copy.deepcopy(arg)
        try:
            model = parse_model(tomli_w.dumps(doc)).model
        except Exception:  # refused at load (the CLI's contract is fuzzed by bench/fuzz.py)
            continue
        if not model.preloaded:
            continue
        try:
            model.operating_point(1000 * math.pi / 30)
            outcomes["found"] += 1
        except ModelError as exc:
            text = str(exc)
            outcomes["refused: " + " ".join(text.split()[:4])] += 1
            if "equilibrium not found" in text:
                bad.append(f"{path} {kind} {arg!r}: {text[:300]}")
        except Exception as exc:  # not a refusal: a finding
            outcomes[f"error: {type(exc).__name__}"] += 1
            bad.append(f"{path} {kind} {arg!r}: {type(exc).__name__}: {str(exc)[:300]}")
    reached = sum(outcomes.values())
    print(f"{len(cases)} mutations, {reached} reach the equilibrium, "
          f"{time.process_time() - t0:.0f} CPU s")  # fmt: skip
    for k, v in outcomes.most_common():
        print(f"  {v:5d}  {k}")
    print("findings:" if bad else "no finding", *bad, sep="\n  ")


if __name__ == "__main__":
    main()
