"""The small-gain bound of a band's modes left out, in the energy norm (docs/stability.md, 8.3).

References, each independent of the code under test:

* the dense decomposition of the time-averaged pencil (every mode, QZ): the transfer function
  of the modes left out is the sum over them, and its loop gain in the energy norm is a dense
  matrix norm through a Cholesky factor of ``S``;
* the dense lattice method (every mode) on the same gearbox: the verdict and the exponents
  that the band method decides in the energy norm, where the balanced norm cannot.
"""

from __future__ import annotations

import importlib
import itertools

import numpy as np
import pytest
import scipy.linalg as sla

import rheolin as rl
from rheolin.data import example_text
from rheolin.floquet.averaged import Averaged
from rheolin.floquet.band import BandAveraged, _top_frequency, certify
from rheolin.floquet.scan import Scan
from rheolin.io import parse_model

RPM = np.pi / 30


@pytest.fixture(scope="module")
def gearbox() -> rl.PeriodicSystem:
    """The example gearbox (126 DOF) at 3000 rpm, in the inertial frame: its intermediate
    shaft has a flat and carries two gears, so its stiffness varies on all its DOFs."""
    model = parse_model(example_text("gearbox")).model
    return model.assemble(3000 * RPM).system


def _dense(x) -> np.ndarray:
    return np.asarray(x.toarray() if hasattr(x, "toarray") else x)


def _left_out(system: rl.PeriodicSystem, band: BandAveraged, sigma: float):
    """``G_C(s)`` as the sum over the time-averaged modes outside the band (dense QZ):
    ``x_j w_j^H (1/(s - lambda_j) - 1/(s - sigma))``."""
    avg = Averaged(system)
    n = system.n
    outside = np.array([np.min(np.abs(band.lam - z)) > 1e-7 * abs(z) for z in avg.lam], dtype=bool)
    assert outside.sum() == avg.lam.size - band.lam.size
    Xq = (avg.X[:n] / avg.sq[:, None])[:, outside]
    Wv = (avg.W[n:] / avg.sv[:, None])[:, outside]
    lam = avg.lam[outside]

    def G_C(s: complex) -> np.ndarray:
        return (Xq * (1 / (s - lam) - 1 / (s - sigma))) @ Wv.conj().T

    return G_C


def test_complement_is_the_sum_over_the_modes_left_out(gearbox, monkeypatch) -> None:
    """The scan's loop ``G_C(s) E_k`` and its adjoint (a sparse LU of ``Q0(s)`` minus the
    band's part, the band's left vectors on the DOFs of ``E_k`` only) equal the sum over the
    modes left out, in and off the right half-plane, for every harmonic (each taken as
    touching many DOFs: ``LOW_RANK`` 0); ``G_C`` decays as ``1/s^2`` as a second-order
    transfer function does (the band's ``1/s`` tail is split off)."""
    monkeypatch.setattr(importlib.import_module("rheolin.floquet.scan"), "LOW_RANK", 0)
    band = BandAveraged(gearbox, 40)
    scan = Scan(gearbox, band)
    assert scan.many
    reference = _left_out(gearbox, band, scan.sigma)
    rng = np.random.default_rng(3)
    x = rng.standard_normal(gearbox.n) + 1j * rng.standard_normal(gearbox.n)
    for s in (0.02j, 3.1e3j, 50.0 + 2.2e4j, 9e5j):
        lu = scan.factor(abs(s)) if s.real == 0 else _lu(scan, s)
        G = reference(s)
        for k, (_, K, D, M) in ((k, scan.parts[k]) for k in scan.many):
            E = _dense(K if K is not None else 0 * np.eye(gearbox.n)) + 0j
            for part, f in ((D, s), (M, s * s)):
                if part is not None:
                    E = E + f * _dense(part)
            apply, adjoint = scan._loop(lu, s, k, E)
            want, back = G @ (E @ x), E.conj().T @ (G.conj().T @ x)
            # norm-wise: E x spans the stiffness's range, and its small entries carry the
            # rounding of the large ones
            assert np.linalg.norm(apply(x) - want) <= 1e-7 * np.linalg.norm(want), (k, s)
            assert np.linalg.norm(adjoint(x) - back) <= 1e-7 * np.linalg.norm(back), (k, s)
    high = [np.linalg.norm(reference(1j * w), 2) for w in (1e7, 1e8)]
    assert high[0] / high[1] == pytest.approx(100.0, rel=0.05)


def _lu(scan: Scan, s: complex):
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    return spla.splu(sp.csc_array(scan.K0 + s * scan.D0 + s * s * scan.M0))


def _dense_loop(gearbox: rl.PeriodicSystem, band: BandAveraged, scan: Scan, exact: bool = True):
    """``(kappa_C, q_S)`` at ``omega`` from the dense sum over the modes left out, each
    harmonic's input norm the smaller bound of ``N(omega_hi)`` and ``alpha S`` (``exact``: as
    the scan takes it for the harmonics that touch few DOFs), else the one of smaller worst
    case (as for the others, by Lanczos)."""
    S = _dense(scan.weight[0])
    Ms = _dense(gearbox.M[0])
    Ms = (Ms + Ms.T) / 2
    mu = scan.family.mu
    L_S = np.linalg.cholesky(S)
    reference = _left_out(gearbox, band, scan.sigma)
    w = gearbox.omega
    zero = np.zeros((gearbox.n,) * 2)
    parts = {
        k: [_dense(t.get(k, zero)) for t in (gearbox.K, gearbox.D, gearbox.M)]
        for k in gearbox.coefficient_harmonics
    }

    def alpha(omega: float) -> float:
        return mu / (mu + omega**2)

    def loop(omega: float) -> tuple[float, float]:
        s = 1j * omega
        G = reference(s)
        hi = max(abs(omega - k * w) for k in parts)
        L = np.linalg.cholesky(alpha(omega) * (S + omega**2 * Ms))
        L_hi = np.linalg.cholesky(alpha(hi) * (S + hi**2 * Ms))
        kappa = qs = 0.0
        for k, (K, D, M) in parts.items():
            sk = s - 1j * k * w
            A = G @ (K + sk * D + sk * sk * M)
            a = alpha(abs(omega - k * w))
            scaled, at_hi = (
                np.linalg.norm(L.conj().T @ sla.solve_triangular(Lin, A.T, lower=True).T, 2)
                for Lin in (np.sqrt(a) * L_S, L_hi)
            )
            if exact:
                kappa += min(scaled, at_hi)
            else:
                kappa += at_hi if a / alpha(hi) < 1 / a else scaled
            qs += float(np.sum(np.linalg.norm(L.conj().T @ (A @ scan.Xq), axis=0)))
        return kappa, qs

    return loop


@pytest.mark.parametrize("low_rank", [96, 0])
def test_loop_gain_in_the_energy_norm_matches_the_dense_norm(
    gearbox, monkeypatch, low_rank
) -> None:
    """``kappa_C(s) = sum_k ||G_C(s) E_k(s - i k w1)||`` into ``N(omega) = mu / (mu +
    omega^2) (S + omega^2 M_s)`` from an input norm no larger than ``N(omega_k)``,
    ``omega_k = |omega - k w1|``: ``N(omega_hi)`` (``omega_hi = max_k omega_k``) or
    ``alpha(omega_k) S`` (``alpha(w) = mu / (mu + w^2)``), the smaller bound of the two for
    the harmonics that touch few DOFs (exact low-rank blocks), the one of smaller worst case
    for the others (Lanczos), both ways for every harmonic; against the dense operator norms
    ``||L_out^H G_C E_k L_in^-H||_2`` (``N = L L^H``), and ``q_S = sum_k sum_m ||G_C(s) E_k
    x_m||_N(omega)`` over the band's displacement vectors against the same dense products."""
    monkeypatch.setattr(importlib.import_module("rheolin.floquet.scan"), "LOW_RANK", low_rank)
    band = BandAveraged(gearbox, 80)
    scan = Scan(gearbox, band)
    assert scan.weight is not None and scan.family.varying
    loop = _dense_loop(gearbox, band, scan, exact=bool(low_rank))
    for omega in (0.5, 2.0e3, 1.2e5, 3.0e7):
        dense, coupled = loop(omega)
        kappa, qs = scan._energy(scan.factor(omega), 1j * omega)
        assert kappa == pytest.approx(dense, rel=1e-5 if low_rank == 0 else 1e-7), omega
        assert qs == pytest.approx(coupled, rel=1e-7), omega


def test_band_decided_in_the_energy_norm_matches_the_dense_method(gearbox) -> None:
    """The gearbox with 80 of its 252 time-averaged modes: in the balanced state's norm the
    modes left out cannot be bounded (``kappa_C >= 1``), in the energy norm they are; the band
    method then decides, with the dense method's verdict and leading exponent (every mode)."""
    band = BandAveraged(gearbox, 80)
    scan = Scan(gearbox, band)
    top = _top_frequency(gearbox, band)
    assert scan.scan(top, 1.0, ("balanced",))["balanced"].kappa >= 1.0
    energy = certify(gearbox, band)
    assert energy.certified and energy.norm == "energy" and energy.kappa < 1.0

    dense = rl.floquet(gearbox)
    res = rl.floquet(gearbox, band=80)
    assert res.info["band"]["norm"] == "energy" and res.info["band"]["certified"]
    assert dense.decided and res.decided and res.stable is dense.stable
    assert abs(res.max_real - dense.max_real) <= res.max_real_uncertainty + 1e-6 * abs(
        dense.max_real
    )
    # every exponent the band method reports is one of the dense method's, or lies in the
    # disc of a cluster the dense method certified without computing it
    w = gearbox.omega
    skipped = dense.info["certified_modes"]
    radii = dense.info["certified_radii"]
    for z, u in zip(res.exponents, res.info["uncertainty"] + res.tolerances, strict=True):
        gap = np.abs(dense.exponents.real - z.real) + np.abs(
            (dense.exponents.imag - z.imag + w / 2) % w - w / 2
        )
        inside = np.any(np.abs(z - skipped) <= radii) or np.any(np.abs(z - skipped.conj()) <= radii)
        assert gap.min() <= 2 * u + 1e-9 * max(abs(z), w) or inside, z


def test_band_grows_past_a_failure_after_a_near_miss(monkeypatch) -> None:
    """The gearbox in its 96,888-DOF housing with fine shafts (bench/results/scale_fine.md):
    ``kappa_C`` 1.02 with 40 modes, 0.88 with 80 (above its limit 0.5), 1.05 with 160 (a
    mode just above that band's radius), 0.20 with 320. Stopping early needs the last two
    sizes in a row to have failed (``hopeless``); 40 and 160 are not, so the band grows to
    320 and is certified there. The band and its scan are stand-ins that replay those
    values."""
    band_module = importlib.import_module("rheolin.floquet.band")
    complement_module = importlib.import_module("rheolin.floquet.complement")
    replay = {40: 1.024, 80: 0.876, 160: 1.049, 320: 0.201}

    class Band:
        def __init__(self, system: object, k: int) -> None:
            self.lam = np.zeros(k)

    def scanned(system: object, band: Band, stop: float = 1.0) -> object:
        kappa = replay[band.lam.size]
        return complement_module.Complement(
            certified=kappa < 1.0 and kappa <= stop, kappa=kappa, energy=True
        )

    monkeypatch.setattr(band_module, "BandAveraged", Band)
    monkeypatch.setattr(band_module, "certify", scanned)
    system = type("System", (), {"n": 1000})()
    band = band_module.band_modes(system)
    assert band.lam.size == 320 and band.complement.certified
    # two failures in a row that would not shrink below 1 at the next size do stop it
    replay[80] = 1.03
    assert band_module.band_modes(system).lam.size == 80


def test_band_stops_below_the_cluster_of_stiffness_proportional_damping() -> None:
    """A chain of 300 unit masses on springs of 1e6 N/m with ``D = beta K``, ``beta = 0.01``
    s: every mode above ``2 / beta`` is overdamped, and one root of each lies near
    ``-1/beta = -100`` 1/s (about 270 of them). A band of 120 roots nearest 0 would end inside
    that cluster, where ARPACK does not converge; the band is the roots below it instead,
    every root of the dense spectrum within its radius and no other, in seconds."""
    import time

    n = 300
    main = 2e6 * np.ones(n)
    main[-1] = 1e6
    off = -1e6 * np.ones(n - 1)
    K = np.diag(main) + np.diag(off, 1) + np.diag(off, -1)
    system = rl.PeriodicSystem(1.0, M={0: np.eye(n)}, D={0: 0.01 * K}, K={0: K})
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-K, -0.01 * K]])
    roots = sla.eigvals(A)
    cluster = np.abs(roots + 100.0) < 5.0
    assert cluster.sum() > 200  # the accumulation point is there
    start = time.process_time()
    band = BandAveraged(system, 120)
    assert time.process_time() - start < 30.0
    inside = roots[np.abs(roots) <= band.radius * (1 + 1e-9)]
    assert 8 <= band.lam.size < 120
    assert band.lam.size == inside.size  # complete within its radius
    assert np.all(np.abs(band.radius - 100.0) > 0)
    assert np.max(np.abs(np.sort_complex(band.lam) - np.sort_complex(inside))) < 1e-6 * 100
    assert not np.any(np.abs(band.lam + 100.0) < 5.0)  # none of the cluster's


def test_the_norms_of_the_scan_come_from_an_analytic_factor() -> None:
    """What the small-gain argument needs of the frequency's norms
    (:class:`~rheolin.floquet.energy_norm.EnergyFamily`), on a random stiffness and mass:
    ``N(omega) = F(i omega)^H F(i omega)`` with ``F(s) = (I + s L^1/2) V^-1 / (1 + s /
    sqrt(mu))`` (``V^T S V = I``, ``V^T M V = L``: analytic and invertible for ``Re s >= 0``);
    ``||F(s) x||^2 >= mu x^H M x`` there (the dual norms' bound); and ``N`` decreasing with
    the frequency (the largest shifted frequency gives the smallest input norm)."""
    from rheolin.floquet.energy_norm import EnergyFamily

    rng = np.random.default_rng(7)
    n = 12
    A = rng.standard_normal((n, n))
    K = A @ A.T * 1e4  # stiffness with a spread of frequencies
    B = rng.standard_normal((n, n))
    M = B @ B.T + n * np.eye(n)
    family = EnergyFamily(K, M, radius=30.0)
    mu = family.mu
    S = K + mu * M
    lam, V = sla.eigh(S, M)  # S V = M V lam, V^T M V = I
    # V^T S V = I and V^T M V = L from the same vectors, scaled
    V = V / np.sqrt(lam)[None, :]
    L = 1.0 / lam
    assert np.allclose(V.T @ S @ V, np.eye(n), atol=1e-9)
    assert np.allclose(V.T @ M @ V, np.diag(L), atol=1e-12)
    Vi = np.linalg.inv(V)

    def F(s: complex) -> np.ndarray:
        return (np.eye(n) + s * np.diag(np.sqrt(L))) @ Vi / (1 + s / np.sqrt(mu))

    for omega in (0.0, 3.0, 30.0, 300.0, 3e4):
        N = family.output(omega)
        N = N.toarray() if hasattr(N, "toarray") else N
        Fi = F(1j * omega)
        assert np.allclose(Fi.conj().T @ Fi, N, rtol=1e-9, atol=1e-9 * np.abs(N).max())
    for _ in range(50):
        s = abs(rng.standard_normal()) * 10 ** rng.uniform(
            -2, 4
        ) + 1j * rng.standard_normal() * 10 ** rng.uniform(-2, 4)
        x = rng.standard_normal(n) + 1j * rng.standard_normal(n)
        assert np.linalg.norm(F(s) @ x) ** 2 >= mu * np.real(x.conj() @ M @ x) * (1 - 1e-12)
    grid = [0.0, 1.0, 10.0, 100.0, 1e3, 1e5]
    for lo, hi in itertools.pairwise(grid):
        gap = _dense(family.output(lo)) - _dense(family.output(hi))
        assert np.linalg.eigvalsh((gap + gap.T) / 2).min() >= -1e-9 * np.abs(gap).max()


def test_the_scan_below_half_the_band_radius_misses_no_peak(gearbox) -> None:
    """Below ``QUIET`` times the band's radius ``R`` no pole of the loop lies nearer than
    ``R - omega`` (every time-averaged eigenvalue inside ``R`` is a band mode), and the scan
    steps there by a fraction of that distance: a handful of points where the geometric grid
    had a dozen. On the gearbox with 80 band modes, the loop's ``kappa_C`` and ``q_S`` (dense
    sums over the modes left out) on 150 frequencies below ``QUIET R`` rise by at most 1 %
    above their largest value at the scan's points there (and the first point above)."""
    from rheolin.floquet.scan_grid import PER_OCTAVE, QUIET, scan_grid

    band = BandAveraged(gearbox, 80)
    scan = Scan(gearbox, band)
    assert not scan.many  # every harmonic's norm exact (low rank), as in the dense loop
    radius = band.radius
    low = float(np.min(np.abs(band.lam))) / 10
    grid = scan_grid(low, _top_frequency(gearbox, band), radius)
    quiet = grid[grid < QUIET * radius]
    assert quiet.size <= 4 < PER_OCTAVE * np.log2(QUIET * radius / low)
    loop = _dense_loop(gearbox, band, scan)
    sampled = np.array([loop(w) for w in grid[: quiet.size + 1]])
    fine = np.array([loop(w) for w in np.geomspace(low, QUIET * radius, 150)])
    assert np.all(fine.max(axis=0) <= 1.01 * sampled.max(axis=0)), (fine.max(0), sampled.max(0))
    # the scan's own values at its points are the dense ones
    kappa, qs = scan._energy(scan.factor(float(quiet[1])), 1j * float(quiet[1]))
    assert (kappa, qs) == pytest.approx(tuple(loop(float(quiet[1]))), rel=1e-6)
