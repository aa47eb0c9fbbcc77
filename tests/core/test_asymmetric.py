"""Non-axisymmetric rotors at full strength (the catalogue of tests/core/asymmetric.py):
every case converges to rtol 1e-10 with ``auto`` and agrees with ``direct``; strong, wide
asymmetry takes the band preconditioner instead of stalling. Near the asymmetric Jeffcott
rotor's instability band (closed form) the response is exact on the stable side and never a
success inside."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from cases import Jeffcott

import rheolin as rl
from asymmetric import ASYMMETRIES, DAMPINGS, FRACTIONS, SPEEDS, shaft


@pytest.mark.parametrize(
    "planes, expected", [(False, {"support", "full", "band"}), (True, {"support", "pairs"})]
)
def test_catalogue_converges_and_agrees_with_direct(planes, expected):
    """4 asymmetries x 3 extents x 3 dampings x 3 speeds (108 cases, 80 DOF): ``auto``
    (gmres) reaches rtol 1e-10 and ``direct`` (sparse LU of the assembled coupled matrix)
    agrees to 1e-9. Without the nodes' planes the A0 strategies occur (support, full, band);
    with them every wide asymmetry takes the whirl-pair chains, exact here (isotropic
    supports): one iteration."""
    strategies, bad = set(), []
    for a, frac, zeta, W in itertools.product(ASYMMETRIES, FRACTIONS, DAMPINGS, SPEEDS):
        s, H = shaft(40, a, frac, zeta, W, planes=planes)
        sol = rl.solve(s, H, stability=False)
        ref = rl.solve(s, H, method="direct", stability=False)
        err = np.abs(sol.q - ref.q).max() / np.abs(ref.q).max()
        strategies.add(sol.info.get("strategy"))
        if not (sol.success and sol.method == "gmres" and sol.residual <= 1e-10 and err < 1e-9):
            bad.append((a, frac, zeta, W, sol.method, sol.message, err))
        if sol.info.get("strategy") == "pairs" and sol.iterations > 2:
            bad.append((a, frac, zeta, W, "pairs took", sol.iterations))
    assert not bad, bad
    assert strategies == expected, strategies


def test_band_preconditioner_where_a0_alone_stalls(monkeypatch):
    """Delta K / K = 20 % over a whole 400-DOF shaft, harmonics over its band of modes:
    A0-preconditioned gmres alone has not converged after 300 iterations; ``auto`` probes 20,
    switches to the band preconditioner, converges, says so, and matches ``direct``."""
    from rheolin.solvers import krylov

    s, H = shaft(200, 0.20, 1.0, 0.02, 1500.0)
    with monkeypatch.context() as m:
        m.setattr(krylov, "PROBE_ITERATIONS", 10**6)  # never switch
        stalled = rl.solve(s, H, method="gmres", maxiter=300, stability=False)
    assert not stalled.success and stalled.iterations == 300
    sol = rl.solve(s, H, stability=False)
    assert sol.success and sol.info["strategy"] == "band", sol.message
    assert "switched to the band preconditioner" in sol.message
    assert sol.iterations <= 40
    ref = rl.solve(s, H, method="direct", stability=False)
    assert np.abs(sol.q - ref.q).max() < 1e-9 * np.abs(ref.q).max()


def _edges(r: Jeffcott) -> tuple[float, float] | None:
    """Speeds where ``(k_x - m W^2)(k_y - m W^2) + c^2 W^2 = 0``, a quadratic in ``W^2``."""
    b = r.m * (r.kx + r.ky) - r.c**2
    disc = b * b - 4 * r.m**2 * r.kx * r.ky
    if disc <= 0:
        return None
    lo, hi = (b - np.sqrt(disc)) / (2 * r.m**2), (b + np.sqrt(disc)) / (2 * r.m**2)
    return float(np.sqrt(lo)), float(np.sqrt(hi))


@pytest.mark.parametrize("zeta", [0.005, 0.02, 0.05])
@pytest.mark.parametrize("asymmetry", [0.01, 0.05, 0.10, 0.20])
def test_jeffcott_two_percent_outside_the_band_and_inside(asymmetry, zeta):
    """Closed-form unbalance response (cases.Jeffcott) 2 % outside each edge on the stable
    side, stable verdict; inside the band (where damping leaves one), status 4."""
    km = 1.0
    kx, ky = km * (1 + asymmetry / 2), km * (1 - asymmetry / 2)
    c = 2 * zeta * np.sqrt(km)
    edges = _edges(Jeffcott(W=1.0, kx=kx, ky=ky, c=c))
    speeds = [0.98, 1.02] if edges is None else [0.98 * edges[0], 1.02 * edges[1]]
    for W in speeds:
        r = Jeffcott(W=W, kx=kx, ky=ky, c=c)
        assert not r.unstable
        H = rl.HarmonicSet.full(5)
        sol = rl.solve(r.system(), H)
        assert sol.success and sol.stable, sol.message
        want = r.unbalance_response(H.indices)
        assert np.abs(sol.q - want).max() < 1e-9 * np.abs(want).max()
    if edges is not None:
        r = Jeffcott(W=float(np.mean(edges)), kx=kx, ky=ky, c=c)
        assert r.unstable
        sol = rl.solve(r.system(), rl.HarmonicSet.full(5))
        assert not sol.success and sol.status == 4, sol.message


def test_whirl_pairs_where_the_chains_are_not_exact():
    """The pairs preconditioner holds the rotating asymmetry exactly on isotropic supports.
    With a 20 % anisotropic foundation (A0 couples f and b) gmres corrects what the chains
    leave out; an asymmetry turning backward swaps the f/b roles (the chains follow it, and
    are exact again). Both converge and match ``direct``."""
    import scipy.sparse as sp

    for case in ("anisotropic", "backward"):
        s, H = shaft(200, 0.20, 1.0, 0.02, 1500.0, planes=True)
        K0 = sp.csr_array(s.K[0])
        if case == "anisotropic":
            K0 = K0 + sp.diags_array(np.tile([2e5, 0.0], 200))
            s = rl.PeriodicSystem(s.omega, M=s.M, D=s.D, K={0: K0, 2: s.K[2]}, f=s.f)
        else:
            K2 = sp.csr_array(s.K[2]).conj()  # the same asymmetry turning the other way
            s = rl.PeriodicSystem(s.omega, M=s.M, D=s.D, K={0: K0, 2: K2}, f=s.f)
        s.whirl_pairs = (2 * np.arange(200), 2 * np.arange(200) + 1)
        sol = rl.solve(s, H, stability=False)
        ref = rl.solve(s, H, method="direct", stability=False)
        assert sol.success and sol.method == "gmres", (case, sol.message)
        assert np.abs(sol.q - ref.q).max() < 1e-9 * np.abs(ref.q).max(), case
        assert sol.info["strategy"] == "pairs" and "100% of the rotating" in sol.message
        if case == "anisotropic":
            assert 1 < sol.iterations < 40, sol.message
        else:
            assert sol.iterations == 1, sol.message
