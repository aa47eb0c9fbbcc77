"""Exact speed propagation, base frequency and the hunting-tooth harmonic count."""

from __future__ import annotations

import itertools
import types
from fractions import Fraction

import pytest

import rheolin as rl
from rheolin.errors import ModelError
from rheolin.mechanics.speeds import GearPair, propagate_speeds, rational_gcd, speed_plan

STAGES = [GearPair("input", "intermediate", 23, 61), GearPair("intermediate", "output", 19, 47)]


def test_two_stage_hunting_tooth_speeds_and_base_frequency():
    plan = speed_plan("input", STAGES)
    # by hand: external pairs reverse, ratio = teeth quotient
    assert plan.ratios == {
        "input": 1,
        "intermediate": Fraction(-23, 61),
        "output": Fraction(23 * 19, 61 * 47),
    }
    # every generator is an integer multiple of w1, and no larger w1 would do
    assert plan.base == Fraction(1, 61 * 47) == Fraction(1, 2867)
    assert plan.spin == {"input": 2867, "intermediate": -1081, "output": 437}
    assert plan.mesh == (23 * 2867, 19 * 1081)
    for g in [*plan.ratios.values(), 23, Fraction(19 * 23, 61)]:
        assert (Fraction(g) / plan.base).denominator == 1
    for bigger in (2, 3, 19, 23, 47, 61):
        coarser = bigger * plan.base
        assert any((Fraction(g) / coarser).denominator != 1 for g in plan.ratios.values())


def _closure_by_hand(seeds, gens, order, cap):
    """Plain enumeration: every seed plus sums of at most `order` signed generators."""
    steps = [0] + [s * g for g in gens for s in (1, -1)]
    out = set()
    for seed in seeds:
        for combo in itertools.product(steps, repeat=order):
            # keep only paths whose partial sums stay within the cut-off
            n, ok = seed, abs(seed) <= cap
            for c in combo:
                n += c
                ok = ok and abs(n) <= cap
            if ok:
                out.add(n)
    return out


def test_hunting_tooth_closure_keeps_hundreds_of_harmonics():
    """Rule: seeds = gravity (0) and once-per-rev unbalance of each shaft; generators = shaft
    and mesh harmonics; order 2; cut-off at twice the highest mesh frequency."""
    plan = speed_plan("input", STAGES)
    seeds = {0} | {s * x for x in plan.spin.values() for s in (1, -1)}
    cap = 2 * max(plan.mesh)
    system_like = types.SimpleNamespace(load_harmonics=sorted(seeds), coefficient_harmonics=[])
    H = rl.HarmonicSet.closure(system_like, order=2, max_harmonic=cap, generators=plan.generators)
    assert set(H.indices.tolist()) == _closure_by_hand(seeds, plan.generators, 2, cap)
    assert len(H) == 213
    assert 2 * cap + 1 == 263765  # the dense grid -N..N to the same cut-off


def test_internal_pair_keeps_direction_and_rational_gcd():
    r = propagate_speeds("sun", [GearPair("sun", "ring", 20, 80, internal=True)])
    assert r["ring"] == Fraction(1, 4)
    assert rational_gcd([Fraction(3, 4), Fraction(9, 10), 0]) == Fraction(3, 20)


def test_inconsistent_train_and_bad_teeth_raise():
    loop = [GearPair("a", "b", 10, 20), GearPair("b", "c", 10, 20), GearPair("a", "c", 10, 30)]
    with pytest.raises(ModelError, match="inconsistent"):
        propagate_speeds("a", loop)
    with pytest.raises(ModelError, match="pinion_teeth"):
        GearPair("a", "b", 0, 20)
    with pytest.raises(ModelError, match="load_ratios"):
        speed_plan("a", [GearPair("a", "b", 10, 20)]).harmonic(Fraction(1, 3))
