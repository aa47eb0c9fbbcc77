"""Sizes are refused before any work, with the estimate and what to change: the memory budget
honours the process's own limits (``ulimit -v``, cgroups), a harmonic set or a lattice too
large for it is refused before it is built, and so is a model too large to assemble."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

import rheolin as rl
import rheolin.budget as budget
from rheolin.budget import MemoryBudgetError
from rheolin.data import example_text
from rheolin.errors import ModelError


def _cgroup_tree(tmp_path, v2: bool, limit: int, used: int):
    root = tmp_path / "cgroup"
    if v2:
        group = root / "user.slice" / "job"
        group.mkdir(parents=True)
        (group / "memory.max").write_text(f"{limit}\n")
        (group / "memory.current").write_text(f"{used}\n")
        listing = "0::/user.slice/job\n"
    else:
        group = root / "memory" / "job"
        group.mkdir(parents=True)
        (group / "memory.limit_in_bytes").write_text(f"{limit}\n")
        (group / "memory.usage_in_bytes").write_text(f"{used}\n")
        listing = "12:pids:/job\n4:memory:/job\n"
    (tmp_path / "self_cgroup").write_text(listing)
    return root, tmp_path / "self_cgroup"


@pytest.mark.parametrize("v2", [True, False])
def test_cgroup_limit_caps_the_budget(tmp_path, monkeypatch, v2):
    """A job limited to 3 GB, 1 GB of it in use: 2 GB of room, whatever the machine has;
    the default budgets are shares of it and an explicit one is capped by it."""
    root, listing = _cgroup_tree(tmp_path, v2, 3 * 10**9, 10**9)
    assert budget._cgroup_room(root, listing) == 2 * 10**9
    monkeypatch.setattr(budget, "_cgroup_room", lambda: 2 * 10**9)
    monkeypatch.setattr(budget, "_machine_available", lambda: 64 * 10**9)
    monkeypatch.setattr(budget, "_address_space_room", lambda: None)
    monkeypatch.delenv("RHEOLIN_MEMORY_BUDGET", raising=False)
    monkeypatch.delenv("RHEOLIN_SOLVE_MEMORY", raising=False)
    assert budget.available_memory() == 2 * 10**9
    assert budget.memory_budget() == 10**9  # half the room
    assert budget.solve_budget() == int(budget.SOLVE_SHARE * 2 * 10**9)
    monkeypatch.setenv("RHEOLIN_SOLVE_MEMORY", "32 GB")
    assert budget.solve_budget() == 2 * 10**9  # never above what the process can allocate


def test_unlimited_cgroup_is_no_limit(tmp_path):
    root, listing = _cgroup_tree(tmp_path, False, 9223372036854771712, 10**9)
    assert budget._cgroup_room(root, listing) is None


def test_address_space_limit_refuses_a_solve_instead_of_running_out_of_memory():
    """Under ``ulimit -v`` (RLIMIT_AS) 600 MB above what the interpreter already maps, a
    solve whose vectors alone need about 1.3 GB is refused with the estimate (the budget
    read from the machine's memory would let it start and die with MemoryError)."""
    code = textwrap.dedent(
        """
        import resource, numpy as np, rheolin as rl
        from rheolin.budget import MemoryBudgetError, _status_bytes
        used = _status_bytes("VmSize")
        resource.setrlimit(resource.RLIMIT_AS, (used + 600 * 2**20, resource.RLIM_INFINITY))
        n = 10
        s = rl.PeriodicSystem(1.0, M={0: np.eye(n)}, K={0: 4 * np.eye(n)},
                              f={1: np.ones(n)})
        try:
            rl.solve(s, 10**6)
        except MemoryBudgetError as exc:
            print("refused:", exc)
        """
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "refused: `harmonics`" in run.stdout and "MemoryError" not in run.stderr


def _system() -> rl.PeriodicSystem:
    n = 4
    return rl.PeriodicSystem(
        2.0, M={0: np.eye(n)}, K={0: 9 * np.eye(n), 1: 0.5 * np.eye(n)}, f={1: np.ones(n)}
    )


def test_a_harmonic_set_beyond_the_budget_is_refused_before_it_is_built(monkeypatch):
    import rheolin.harmonics.sets as sets

    def never(*a, **k):
        raise AssertionError("the harmonic set was built before its size was checked")

    monkeypatch.setattr(sets.HarmonicSet, "full", never)
    with pytest.raises(MemoryBudgetError, match=r"`harmonics`: .* 10000001 harmonics x 4 DOF"):
        rl.solve(_system(), 10**7, memory_budget="1 GB")


def test_the_preflight_refuses_a_harmonic_set_only_past_the_count_it_states(monkeypatch):
    """The preflight allows ``budget // per-harmonic bytes`` harmonics and says so; a set of
    that many is accepted and one more refused. It once counted every harmonic twice and
    refused the gearbox with shafts at 50,022 DOF at order 2 (659 harmonics, which solve in
    5.3 GB) as past its 1,007."""
    import re

    from rheolin.io import parse_model
    from rheolin.io.preflight import _per_harmonic, preflight

    lm = parse_model(example_text("rotor"))
    system = lm.model.assemble(lm.spec.model.speed).system
    size = preflight(lm, None).harmonic_count  # the file's set
    per = _per_harmonic(system)
    monkeypatch.setenv("RHEOLIN_SOLVE_MEMORY", str(size * per))
    assert preflight(lm, None).harmonic_count == size  # exactly as many as fit
    monkeypatch.setenv("RHEOLIN_SOLVE_MEMORY", str(size * per - 1))
    with pytest.raises(MemoryBudgetError, match="grows the harmonic set past") as info:
        preflight(lm, None)
    stated = int(re.search(r"past ([0-9,]+) harmonics", str(info.value)).group(1).replace(",", ""))
    assert stated == size - 1


def test_a_harmonic_set_without_any_load_harmonic_is_refused():
    """The loads act at harmonics -1 and 1; a set of 0 and +-2 would answer q = 0."""
    with pytest.raises(ModelError, match=r"`harmonics`: the set leaves out every load harmonic"):
        rl.solve(_system(), [-2, 0, 2])
    s = _system()
    two = rl.PeriodicSystem(s.omega, M=s.M, K=s.K, f={1: np.ones(4), 2: np.ones(4)})
    with pytest.warns(rl.TruncationWarning, match="leaves out 2 of 4 load harmonics"):
        rl.solve(two, [0, 1], method="direct", stability=False)


@pytest.mark.parametrize("order", ["20", "100000"])
def test_frf_lattice_orders_beyond_any_budget_are_refused_naming_the_option(
    invoke, tmp_path, monkeypatch, order
):
    """The gearbox's lattice has 15 generators: order 20 may hold 1.9e8 harmonics, order
    100,000 beyond 1e18 (its size bound is counted in O(order), not convolved)."""
    import rheolin.results.frf as frf

    def never(*a, **k):
        raise AssertionError("the lattice operator was built")

    monkeypatch.setattr(frf, "LatticeHill", never)
    (tmp_path / "g.toml").write_text(example_text("gearbox"))
    res = invoke("frf", tmp_path / "g.toml", "--speed", "3000rpm", "--frequencies",
                 "10:500:10Hz", "--input", "input:3:uy", "--order", order,
                 "--out", tmp_path / "f")  # fmt: skip
    assert res.exit_code == 2, res.stderr
    assert res.stderr.startswith("error: --order: a lattice of order " + order), res.stderr
    assert not (tmp_path / "f").exists()


def test_a_model_too_large_to_assemble_is_refused_before_it_is_built(invoke, tmp_path, monkeypatch):
    """A 100,000-node shaft: refused from its element count (6.4 GB against the budget)."""
    import rheolin.io.loader as loader

    def never(*a, **k):
        raise AssertionError("the model was built")

    monkeypatch.setattr(loader, "build_model", never)
    monkeypatch.setenv("RHEOLIN_MEMORY_BUDGET", "4 GB")
    n = 100_000
    positions = " ".join(f"{600 * i / (n - 1):.6f}" for i in range(n))
    text = example_text("rotor").replace(
        'positions = "0 300 600 mm"', f'positions = "{positions} mm"'
    )
    (tmp_path / "long.toml").write_text(text.replace("node = 2\n", f"node = {n - 1}\n"))
    res = invoke("validate", tmp_path / "long.toml")
    assert res.exit_code == 2, res.stderr
    assert "shafts[0].positions: 99,999 shaft elements" in res.stderr
    assert "memory budget" in res.stderr
