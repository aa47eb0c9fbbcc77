"""Stability maps of assembled models against closed forms (docs/stability.md, docs/solvers.md).

* Asymmetric Jeffcott rotor: a massless shaft with ``I_y != I_z`` and a midspan disk, and a
  rigid rotor on a spring fixed in its own axes; band ``(k_x - m W^2)(k_y - m W^2) + c^2 W^2
  < 0``.
* Gear pair with ``k(t) = k (1 + eps cos W_m t)``: parametric bands from
  ``scipy.special.mathieu_a / mathieu_b``.
* Isotropic rotor with rotating damping ``c_r`` and stationary damping ``c_n``: onset
  ``W_th = w_n (1 + c_n / c_r)``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import mathieu_a, mathieu_b

import rheolin as rl
from rheolin.mechanics import Model
from rheolin.stability import stability_map

sys.path.insert(0, str(Path(__file__).parents[1] / "mechanics"))
from test_model import _asymmetric_rotor

STIFF = 1e6


def _band(m: float, kx: float, ky: float, c: float) -> tuple[float, float]:
    """Roots in W of ``(kx - m W^2)(ky - m W^2) + c^2 W^2 = 0`` (a quadratic in W^2)."""
    x = np.roots([m * m, c * c - m * (kx + ky), kx * ky])
    lo, hi = np.sqrt(np.sort(x.real))
    return float(lo), float(hi)


def test_asymmetric_shaft_band_at_model_level() -> None:
    """Massless Euler-Bernoulli shaft (``kappa = inf``), disk at midspan, bearings of
    ``k_b = 1e11`` N/m (stiff springs next to a 1e6 N/m shaft: a badly scaled system):
    ``1 / k_i = L^3 / (48 E I_i) + 1 / (2 k_b)``."""
    E, L, I1, I2, m, c, kb = 2.1e11, 0.6, 2.0e-8, 2.6e-8, 5.0, 20.0, 1e11
    model = _asymmetric_rotor(I1, I2, E, L, m, c)  # the mechanics test's rotor, k_b = 1e11
    k1, k2 = (1.0 / (L**3 / (48 * E * i) + 1.0 / (2 * kb)) for i in (I1, I2))
    lo, hi = _band(m, k1, k2, c)
    speeds = np.linspace(0.9 * lo, 1.1 * hi, 9)
    smap = stability_map(model, speeds, harmonics=4)
    assert len(smap.ranges) == 1
    r = smap.ranges[0]
    assert r.lower == pytest.approx(lo, rel=1e-7)
    assert r.upper == pytest.approx(hi, rel=1e-7)
    assert r.mechanism == "asymmetric shaft band"
    assert not (r.lower_open or r.upper_open)
    assert smap.converged.all()
    # outside the band: stable, and the worst exponent is a damped one (no false positive
    # from the 1e11 springs or the massless shaft nodes)
    outside = (speeds < lo) | (speeds > hi)
    assert smap.stable[outside].all() and (smap.max_real[outside] < 0).all()
    assert smap.stable.sum() == outside.sum()


@pytest.mark.parametrize("c", [0.0, 15.0])
def test_rigid_rotor_on_rotating_spring_band(c: float) -> None:
    """Rigid rotor, spring in the rotor's axes (k_x != k_y), stationary damping c. Undamped,
    the stable speeds are marginal (all exponents on the axis) and must not be called
    unstable."""
    m, kx, ky = 2.0, 4e3, 1.6e4
    model = Model()
    model.add_rigid_body("rotor", (0, 0, 0), m, (1e-3, 1e-3, 2e-3))
    model.add_bearing("shaft", "rotor", 0, [kx, ky], components=("ux", "uy"), frame="rotor")
    model.add_bearing("support", "rotor", 0, STIFF, 0.0, components=("uz", "phix", "phiy", "phiz"))
    if c:
        model.add_bearing("damper", "rotor", 0, 0.0, c, components=("ux", "uy"))
    lo, hi = _band(m, kx, ky, c)
    speeds = np.linspace(0.5 * lo, 1.5 * hi, 11)
    smap = stability_map(model, speeds, harmonics=4)
    (r,) = smap.ranges
    assert r.lower == pytest.approx(lo, rel=1e-6)
    assert r.upper == pytest.approx(hi, rel=1e-6)
    assert r.mechanism == "asymmetric shaft band"
    if c == 0.0:
        assert smap.marginal[smap.stable].all()
    ds = smap.to_dataset()
    assert ds["range_lower"].values[0] == r.lower and ds.sizes["speed"] == speeds.size


# --------------------------------------------------------------------------- gear pair
J1, J2, Z1, Z2, MODULE, ALPHA, K0, EPS = 2e-4, 1.6e-3, 20, 40, 3e-3, np.radians(20), 1e8, 0.3


def _gear_model(kb: float) -> Model:
    """Two gear blanks; translations and tilts on bearings of stiffness ``kb``, torsion
    free (a rigid-body rotation: a double zero exponent). The centre distance is set by
    the base radii. ``k(t) = K0 (1 + EPS cos W_m t)``."""
    rb1 = MODULE * Z1 / 2 * np.cos(ALPHA)
    rb2 = MODULE * Z2 / 2 * np.cos(ALPHA)
    model = Model(input_body="pinion")
    model.add_rigid_body("pinion", (0, 0, 0), 0.5, (1e-4, 1e-4, J1))
    model.add_rigid_body("gear", ((rb1 + rb2) / np.cos(ALPHA), 0, 0), 2.0, (8e-4, 8e-4, J2))
    for body in ("pinion", "gear"):
        model.add_bearing(body, body, 0, kb, components=("ux", "uy", "uz", "phix", "phiy"))
    model.add_gear_mesh(
        "mesh",
        "pinion",
        0,
        "gear",
        0,
        Z1,
        Z2,
        module=MODULE,
        pressure_angle=ALPHA,
        stiffness={0: K0, 1: K0 * EPS / 2},
    )
    return model


def _mathieu_speed_band(m: int, omega0: float) -> tuple[float, float]:
    """``delta'' + W0^2 (1 + eps cos W_m t) delta = 0``; ``tau = W_m t / 2``: Mathieu with
    ``a = 4 W0^2 / W_m^2``, ``|q| = a eps / 2``. Unstable for ``b_m(q) < a < a_m(q)``."""
    a_lo = brentq(lambda a: a - mathieu_b(m, a * EPS / 2), 0.5 * m * m, 1.5 * m * m)
    a_hi = brentq(lambda a: a - mathieu_a(m, a * EPS / 2), 0.5 * m * m, 1.5 * m * m)
    # W_input = W_m / Z1 = 2 W0 / (Z1 sqrt(a)): a larger a is a lower speed
    return 2 * omega0 / (Z1 * np.sqrt(a_hi)), 2 * omega0 / (Z1 * np.sqrt(a_lo))


@pytest.mark.parametrize("m", [1, 2])
def test_gear_mesh_parametric_bands_against_mathieu(m: int) -> None:
    rb1 = MODULE * Z1 / 2 * np.cos(ALPHA)
    rb2 = MODULE * Z2 / 2 * np.cos(ALPHA)
    omega0 = np.sqrt(K0 * (rb1**2 / J1 + rb2**2 / J2))
    lo, hi = _mathieu_speed_band(m, omega0)
    model = _gear_model(kb=1e13)  # bearings 1e5 times stiffer than the mesh
    mesh = model.speed_plan().mesh[0]
    H = rl.HarmonicSet(mesh * np.arange(0, 5))
    speeds = np.linspace(lo - 0.3 * (hi - lo), hi + 0.3 * (hi - lo), 6)
    smap = stability_map(model, speeds, harmonics=H, refine=1e-6)
    (r,) = smap.ranges
    # the 1e13 bearings shift W0^2 by ~ K0 / kb = 1e-5
    assert r.lower == pytest.approx(lo, rel=2e-5), (r.lower, lo)
    assert r.upper == pytest.approx(hi, rel=2e-5), (r.upper, hi)
    assert r.mechanism == "parametric mesh resonance"
    # 2 w_0 ~ W_m is the principal resonance of the mesh; 2 w_0 ~ 2 W_m the secondary one
    assert r.detail is not None and r.detail.sources == ("mesh mesh",)
    assert r.detail.resonance == ("principal" if m == 1 else "secondary")
    # the free rotation (double zero exponent) keeps the stable speeds marginal, not unstable
    assert smap.marginal[smap.stable].all()


# --------------------------------------------------------------------------- rotating damping
@pytest.mark.parametrize("ratio", [0.0, 0.5, 2.0])
def test_rotating_damping_onset(ratio: float) -> None:
    """Rigid rotor on an isotropic spring k with damping c_r defined in the rotor's axes
    (rotating damping) and a stationary damper c_n: unstable above ``w_n (1 + c_n / c_r)``."""
    m, k, c_r = 2.0, 8e3, 6.0
    c_n = ratio * c_r
    w_n = np.sqrt(k / m)
    W_th = w_n * (1 + c_n / c_r)
    model = Model()
    model.add_rigid_body("rotor", (0, 0, 0), m, (1e-3, 1e-3, 2e-3))
    model.add_bearing("shaft", "rotor", 0, k, c_r, components=("ux", "uy"), frame="rotor")
    model.add_bearing("support", "rotor", 0, STIFF, 1.0, components=("uz", "phix", "phiy", "phiz"))
    if c_n:
        model.add_bearing("damper", "rotor", 0, 0.0, c_n, components=("ux", "uy"))
    speeds = np.linspace(0.5 * W_th, 2.0 * W_th, 7)
    smap = stability_map(model, speeds, harmonics=2)
    (r,) = smap.ranges
    assert r.lower == pytest.approx(W_th, rel=1e-6)
    assert r.upper_open and r.upper == speeds[-1]
    assert r.mechanism == "rotating damping"
    # growth rate of the forward mode: z = x + i y, m z'' + (c_n + c_r) z' + (k - i c_r W) z
    roots = np.roots([m, c_n + c_r, k - 1j * c_r * speeds[-1]])
    assert smap.max_real[-1] == pytest.approx(roots.real.max(), rel=1e-8)


# --------------------------------------------------------------------------- worker processes
@pytest.mark.parametrize("forked", [False, True])
def test_map_on_workers_against_mathieu(forked: bool) -> None:
    """The gear pair's principal band on two worker processes (speeds in contiguous blocks,
    each continued within itself; the bounds refined here afterwards): the Mathieu bounds,
    and speed by speed the verdicts and largest real parts of the map in one process. On the
    workers ``local_workers`` gives, and on forked ones (each verdict reported through the
    executor's queue)."""
    from rheolin.study.executor import ForkExecutor

    rb1 = MODULE * Z1 / 2 * np.cos(ALPHA)
    rb2 = MODULE * Z2 / 2 * np.cos(ALPHA)
    omega0 = np.sqrt(K0 * (rb1**2 / J1 + rb2**2 / J2))
    lo, hi = _mathieu_speed_band(1, omega0)
    model = _gear_model(kb=1e13)
    mesh = model.speed_plan().mesh[0]
    H = rl.HarmonicSet(mesh * np.arange(0, 5))
    speeds = np.linspace(lo - 0.3 * (hi - lo), hi + 0.3 * (hi - lo), 6)
    seen: list[tuple[int, float]] = []
    pool = ForkExecutor(2) if forked else None
    try:
        smap = stability_map(
            model, speeds, harmonics=H, refine=1e-6, workers=2, client=pool,
            progress=lambda i, r: seen.append((i, r.max_real)),
        )  # fmt: skip
    finally:
        if pool is not None:
            pool.close()
    (r,) = smap.ranges
    assert r.lower == pytest.approx(lo, rel=2e-5), (r.lower, lo)
    assert r.upper == pytest.approx(hi, rel=2e-5), (r.upper, hi)
    # each speed reported once, with its result
    assert [i for i, _ in sorted(seen)] == list(range(speeds.size))
    assert [x for _, x in sorted(seen)] == smap.max_real.tolist()
    alone = stability_map(model, speeds, harmonics=H, refine=1e-6)
    assert smap.state.tolist() == alone.state.tolist()
    # each largest real part within 1e-9 of the other, or within its stated tolerance: at the
    # stable speeds it is the neutral rotation's exponent, zero to rounding (2e-8 to 1.2e-7,
    # depending on the BLAS threads of the process; stated tolerance 7e-6 and 1.4e-5)
    gap = np.abs(smap.max_real - alone.max_real)
    assert np.all(gap <= np.maximum(1e-9 * np.abs(alone.max_real), alone.tol)), (gap, alone.tol)
    with pytest.raises(ValueError, match="workers"):
        stability_map(model, speeds, workers=0)
