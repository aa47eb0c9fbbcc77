"""BLAS limited to one thread: overlapping uses from two threads keep the limit while either
is inside, and restore once, when the last one leaves (a fresh process with two BLAS threads:
the suite itself runs with one)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

SCENARIO = r"""
import json, threading
import numpy, scipy.linalg
from threadpoolctl import threadpool_info
from rheolin.linalg import threads as blas_threads
from rheolin.linalg.threads import single_thread_blas

def blas():
    return [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]

before = blas()
first_in, second_in, first_out = threading.Event(), threading.Event(), threading.Event()
seen = {}

def first():
    with single_thread_blas():
        first_in.set()
        second_in.wait(5)
    first_out.set()

def second():
    first_in.wait(5)
    with single_thread_blas():
        second_in.set()
        first_out.wait(5)
        seen["inside"] = blas()  # the first user has left; this one still works

threads = [threading.Thread(target=first), threading.Thread(target=second)]
for t in threads:
    t.start()
for t in threads:
    t.join(10)
state = blas_threads._STATE
print(json.dumps({"before": before, "inside": seen.get("inside"),
                  "left": [state["depth"], state["limits"] is None]}))
"""


def test_overlapping_uses_keep_the_limit_and_release_it_once() -> None:
    env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")}
    env["OPENBLAS_NUM_THREADS"] = "2"
    out = subprocess.run(
        [sys.executable, "-c", SCENARIO], env=env, capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["before"] and max(got["before"]) == 2
    # one thread while any user is inside, though the first has left (plain nested
    # ``threadpool_limits`` would have restored two threads here)
    assert got["inside"] == [1] * len(got["before"])
    # both left: the limit released once, nothing held (the count OpenBLAS then reports
    # after a restore made from another thread than the limit's is its own: 2 alone, 1 under
    # load)
    assert got["left"] == [0, True]
