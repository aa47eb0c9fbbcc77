"""The Floquet verdict on a Craig-Bampton reduction (rheolin.system.reduction,
rheolin.floquet.reduced; docs/stability.md, section 9).

References that do not share the reduction: the monodromy matrix of the full gear variant
(stored, tests/stability/data/gear_variant_ranges.json), the full system's own lattice
verdict, and the full time-averaged eigenvalues of a chain.
"""

from __future__ import annotations

import importlib

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
from gear_variants import reference_ranges, variant_model

import rheolin as rl
from rheolin.errors import ModelError
from rheolin.system.reduction import craig_bampton, local_boundary

reduced = importlib.import_module("rheolin.floquet.reduced")
TRUNCATION_SAFETY = importlib.import_module("rheolin.floquet.result").TRUNCATION_SAFETY


@pytest.fixture(scope="module")
def variant() -> rl.Model:
    return variant_model()


def _chain(n: int = 40) -> rl.PeriodicSystem:
    K = (
        sp.diags_array(
            [np.r_[2.0 * np.ones(n - 1), 1.0], -np.ones(n - 1), -np.ones(n - 1)], offsets=[0, 1, -1]
        ).tocsc()
        * 1e4
    )
    k1 = sp.csc_array(([500.0], ([0], [0])), shape=(n, n))
    return rl.PeriodicSystem(
        3.0, M={0: sp.eye_array(n, format="csc")}, D={0: 1e-4 * K}, K={0: K, 1: k1}
    )


def test_every_mode_kept_is_exact() -> None:
    """Craig-Bampton with every fixed-interface mode is a change of coordinates: the
    time-averaged eigenvalues are the full chain's (a dense eigensolver on both)."""
    s = _chain()
    red = craig_bampton(s, cutoff=1e9)
    assert red.modes == s.n - red.boundary.size

    def eigenvalues(system: rl.PeriodicSystem) -> np.ndarray:
        M, D, K = (system.M[0].toarray(), system.D[0].toarray(), system.K[0].toarray())
        n = M.shape[0]
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-K, -D]])
        B = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), M]])
        return sla.eigvals(A, B)

    full, small = eigenvalues(s), eigenvalues(red.system)
    nearest = np.abs(full[:, None] - small[None, :]).min(axis=1)
    assert small.size == full.size
    assert np.all(nearest <= 1e-9 * np.abs(full))


def test_the_modes_left_out_lie_above_the_cutoff() -> None:
    """What is kept is below the cut-off and the next mode above it; the lowest kept
    frequencies are the fixed-interface chain's (a fixed-free chain of 39 springs:
    ``2 sqrt(k/m) sin((2j - 1) pi / (2 (2 m + 1)))``, m = 39)."""
    s = _chain()
    red = craig_bampton(s, cutoff=60.0)
    assert red.boundary.tolist() == [0]
    assert np.all(red.frequencies <= 60.0) and red.next_frequency > 60.0
    m = 39
    j = np.arange(1, red.modes + 1)
    exact = 2 * 100.0 * np.sin((2 * j - 1) * np.pi / (2 * (2 * m + 1)))
    assert np.allclose(red.frequencies, exact, rtol=1e-10)


def test_boundary_and_refusals() -> None:
    s = _chain()
    assert local_boundary(s).tolist() == [0]
    with pytest.raises(ModelError, match="cutoff"):
        craig_bampton(s, cutoff=-1.0)
    with pytest.raises(ModelError, match="boundary"):
        craig_bampton(s, cutoff=10.0, boundary=np.array([s.n + 3]))
    with pytest.raises(ModelError, match="nothing to reduce"):
        craig_bampton(s, cutoff=10.0, boundary=np.arange(s.n))


@pytest.mark.parametrize("rpm", [3000.0, 3700.0, 4480.0])
def test_reduced_verdict_against_the_monodromy_matrix(variant: rl.Model, rpm: float) -> None:
    """Stable, inside the principal resonance and inside the combination resonance: the
    verdict on the reduction (default cut-off) is decided, says what the full variant's
    monodromy matrix says, and its largest real part is within its stated uncertainty of
    the reference."""
    ref = next(p for p in reference_ranges()["points"] if p["rpm"] == rpm)
    s = variant.assemble(rpm * np.pi / 30).system
    res = reduced.floquet_reduced(s)
    info = res.info["reduction"]
    assert info["dof"] < s.n and info["modes"] > 0
    assert res.decided
    assert res.stable == (ref["max_real"] < 0)
    assert abs(res.max_real - ref["max_real"]) <= res.max_real_uncertainty + ref["error"]


def test_estimate_covers_the_reduction_error(variant: rl.Model) -> None:
    """Against the full system's own lattice verdict, at cut-offs from the default down to
    no fixed-interface mode at all: every reduced exponent lies within its stated reach
    (``TRUNCATION_SAFETY`` times its truncation and reduction estimates) of the nearest
    full exponent, and where the reduction error shows, the estimate's size is that error's
    (the median of their ratio between 0.5 and 2). Inside the principal resonance."""
    s = variant.assemble(3700.0 * np.pi / 30).system
    full = rl.floquet(s, method="lattice")
    for cutoff in (None, 1e5, 2e4):
        res = reduced.floquet_reduced(s, cutoff, steps=0)
        delta = res.info["reduction_estimate"]
        ratios = []
        for j, lam in enumerate(res.exponents):
            k = int(np.argmin(np.abs(full.exponents - lam)))
            err = abs(full.exponents[k] - lam)
            reach = TRUNCATION_SAFETY * (res.truncation[j] + full.truncation[k])
            assert err <= reach + res.tolerances[j] + full.tolerances[k]
            if err > TRUNCATION_SAFETY * full.truncation[k] and abs(delta[j]) > 0:
                ratios.append(err / abs(delta[j]))
        if cutoff is not None:  # a coarse reduction: its error shows
            assert ratios and 0.5 <= float(np.median(ratios)) <= 2.0


def test_too_coarse_a_reduction_is_never_confidently_wrong(variant: rl.Model) -> None:
    """With two fixed-interface modes the verdict at 3000 rpm is left open by the estimate
    or covers the monodromy reference; with the cut-off raised while open it decides."""
    ref = next(p for p in reference_ranges()["points"] if p["rpm"] == 3000.0)
    s = variant.assemble(3000.0 * np.pi / 30).system
    coarse = reduced.floquet_reduced(s, 5e4, steps=0)
    assert coarse.info["reduction"]["modes"] == 2
    assert (not coarse.decided) or abs(coarse.max_real - ref["max_real"]) <= (
        coarse.max_real_uncertainty
    )
    raised = reduced.floquet_reduced(s, 5e4, steps=3)
    tried = raised.info["reduction"]["tried"]
    assert raised.decided and len(tried) > 1
    assert tried[-1]["cutoff"] == pytest.approx(5e4 * 2 ** (len(tried) - 1))
    assert abs(raised.max_real - ref["max_real"]) <= raised.max_real_uncertainty + ref["error"]
