"""Timoshenko beam element against closed forms (frequencies, whirl, asymmetric shaft)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import scipy.linalg as sla

from rheolin.errors import ModelError
from rheolin.mechanics.beam import beam_local_matrices, beam_term
from rheolin.mechanics.rigid import disk
from rheolin.mechanics.sections import (
    Material,
    general_section,
    hollow_circular,
    rectangular,
    solid_circular,
)

STEEL = Material(E=2.1e11, density=7800.0, nu=0.3)
Z = np.array([0.0, 0.0, 1.0])


def _dense(terms, n_dof, key=0):
    out = {name: np.zeros((n_dof, n_dof), dtype=complex) for name in "MDK"}
    for t in terms:
        for name in "MDK":
            x = getattr(t, name).get(key)
            if x is not None:
                out[name][np.ix_(t.dofs, t.dofs)] += x
    return out["M"], out["D"], out["K"]


def _shaft(n_el, length, section, material=STEEL, s=0, w1=1.0, rotary="auto"):
    h = length / n_el
    return [
        beam_term((i, i + 1), h, section, material, Z, Z, s, w1, rotary=rotary) for i in range(n_el)
    ]


def _plane_frequencies(n_el, length, section, keep_ends):
    """Bending frequencies of the x-z plane (DOFs ux, phiy) with the given kept end DOFs."""
    M, _, K = _dense(_shaft(n_el, length, section), 6 * (n_el + 1))
    dofs = [6 * i + 0 for i in range(n_el + 1)] + [6 * i + 4 for i in range(n_el + 1)]
    dofs = [d for d in dofs if d not in keep_ends]
    w2 = sla.eigh(K[np.ix_(dofs, dofs)].real, M[np.ix_(dofs, dofs)].real, eigvals_only=True)
    return np.sqrt(w2)


def _timoshenko_ss(n, length, section, material=STEEL):
    k = n * np.pi / length
    E, _G, rho = material.E, material.G, material.density
    A, I, kGA = section.area, section.Iy, section.kappa_y * material.G * section.area
    a = rho * A * rho * I
    b = rho * A * (E * I * k**2 + kGA) + rho * I * kGA * k**2
    c = kGA * k**2 * E * I * k**2
    return np.sqrt((b - np.sqrt(b * b - 4 * a * c)) / (2 * a))


def test_simply_supported_timoshenko_closed_form_and_convergence():
    L, sec = 0.5, solid_circular(0.1, nu=0.3)  # L/d = 5: shear and rotary inertia matter
    exact = np.array([_timoshenko_ss(n, L, sec) for n in (1, 2, 3)])
    eb = np.array(
        [
            (n * np.pi / L) ** 2 * np.sqrt(STEEL.E * sec.Iy / (STEEL.density * sec.area))
            for n in (1, 2, 3)
        ]
    )
    assert np.all(eb / exact > 1.04)  # the shear correction is not negligible here
    errs, ws = [], []
    for n_el in (5, 10, 20, 40):
        ends = [0, 6 * n_el]  # ux = 0 at both ends, phiy free
        ws.append(_plane_frequencies(n_el, L, sec, ends)[:3])
        errs.append(np.abs(ws[-1] / exact - 1).max())
    # second-order convergence to the closed form (shear-rigid beams converge as h^4, below)
    assert errs[-1] < 1e-3
    assert all(3.5 < e1 / e2 < 4.5 for e1, e2 in itertools.pairwise(errs))
    richardson = (4 * ws[-1] - ws[-2]) / 3
    np.testing.assert_allclose(richardson, exact, rtol=1e-5)


def test_simply_supported_rayleigh_beam_fourth_order():
    L, c = 0.5, solid_circular(0.1)
    sec = general_section(c.area, c.Iy, c.Iz, c.torsion_constant)  # kappa = inf
    k = np.arange(1, 4) * np.pi / L
    rho, E, A, I = STEEL.density, STEEL.E, c.area, c.Iy
    exact = np.sqrt(E * I * k**4 / (rho * A + rho * I * k**2))
    errs = [
        np.abs(_plane_frequencies(n, L, sec, [0, 6 * n])[:3] / exact - 1).max() for n in (10, 20)
    ]
    assert errs[1] < 5e-5 and errs[0] / errs[1] > 12


def test_cantilever_slender_euler_bernoulli():
    L, d = 1.0, 0.005  # slender: L/d = 200, shear rigid
    c = solid_circular(d)
    sec = general_section(c.area, c.Iy, c.Iz, c.torsion_constant)
    w = _plane_frequencies(20, L, sec, [0, 4])[:3]
    bl = np.array([1.8751040687, 4.6940911330, 7.8547574382])
    exact = bl**2 / L**2 * np.sqrt(STEEL.E * sec.Iy / (STEEL.density * sec.area))
    np.testing.assert_allclose(w, exact, rtol=1e-4)


def test_overhung_disk_whirl_closed_form():
    # massless cantilever shaft, rigid disk at the free end, spinning about +z
    L, W = 0.3, 800.0
    sec = general_section(
        *(lambda s: (s.area, s.Iy, s.Iz, s.torsion_constant))(solid_circular(0.02))
    )
    shaft = Material(E=2.1e11, density=0.0, nu=0.3)
    node = disk(0.25, 0.03, 7800.0, axis=Z)
    terms = [beam_term((0, 1), L, sec, shaft, Z, Z, 1, W), node.term(1, Z, 1, W)]
    M, D, K = (x[6:, 6:] for x in _dense(terms, 12))
    keep = [0, 1, 3, 4]  # ux, uy, phix, phiy (axial and torsion decouple)
    M, D, K = (x[np.ix_(keep, keep)].real for x in (M, D, K))
    A = np.block([[np.zeros((4, 4)), np.eye(4)], [-np.linalg.solve(M, K), -np.linalg.solve(M, D)]])
    lam, vec = np.linalg.eig(A)
    fw, bw = [], []
    for lm, v in zip(lam, vec.T, strict=True):
        if lm.imag > 0:
            ux, uy = v[0], v[1]
            (fw if abs(ux + 1j * uy) > abs(ux - 1j * uy) else bw).append(lm.imag)
    # closed form: (k11 - m w^2)(k22 - Id w^2 + W Ip w) = k12^2, w > 0 forward, w < 0 backward
    EI = STEEL.E * sec.Iy
    k11, k12, k22 = np.linalg.inv([[L**3 / (3 * EI), L**2 / (2 * EI)], [L**2 / (2 * EI), L / EI]])[
        [0, 0, 1], [0, 1, 1]
    ]
    m, Id, Ip = node.mass, node.inertia[0, 0], node.inertia[2, 2]
    poly = np.polysub(np.polymul([-m, 0, k11], [-Id, W * Ip, k22]), [k12**2])
    roots = np.sort(np.roots(poly).real)
    np.testing.assert_allclose(np.sort(fw), roots[roots > 0], rtol=1e-10)
    np.testing.assert_allclose(np.sort(bw), np.sort(-roots[roots < 0]), rtol=1e-10)
    assert abs(roots[roots > 0][0] / -roots[roots < 0].max() - 1) > 0.02  # visible split


def test_spinning_simply_supported_rayleigh_shaft_gyroscopic_beam():
    L, d, W = 0.5, 0.05, 3000.0
    c = solid_circular(d)
    sec = general_section(c.area, c.Iy, c.Iz, c.torsion_constant)  # shear rigid: Rayleigh beam
    n_el = 24
    terms = _shaft(n_el, L, sec, s=1, w1=W)
    M, D, K = (x.real for x in _dense(terms, 6 * (n_el + 1)))
    dofs = [6 * i + j for i in range(n_el + 1) for j in (0, 1, 3, 4)]
    dofs = [q for q in dofs if q not in (0, 1, 6 * n_el, 6 * n_el + 1)]
    M, D, K = (x[np.ix_(dofs, dofs)] for x in (M, D, K))
    n = len(dofs)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, D)]])
    lam, vec = np.linalg.eig(A)
    fw, bw = [], []
    for lm, v in zip(lam, vec.T, strict=True):
        if lm.imag > 0:
            ux, uy = v[0::4][:n_el], v[1::4][:n_el]
            f_amp = np.linalg.norm(ux + 1j * uy)
            (fw if f_amp > np.linalg.norm(ux - 1j * uy) else bw).append(lm.imag)
    fw, bw = np.sort(fw)[:2], np.sort(bw)[:2]
    rho, E, A_, I = STEEL.density, STEEL.E, sec.area, sec.Iy
    for mode in (1, 2):
        k = mode * np.pi / L
        # (rho A + rho I k^2) w^2 - rho Ip W k^2 w - EI k^4 = 0; forward root > 0
        r = np.roots([rho * A_ + rho * I * k**2, -rho * 2 * I * W * k**2, -E * I * k**4])
        assert fw[mode - 1] == pytest.approx(r.max(), rel=1e-5)
        assert bw[mode - 1] == pytest.approx(-r.min(), rel=1e-5)
    assert fw[0] / bw[0] - 1 > 5e-3


def test_asymmetric_shaft_stiffness_varies_at_twice_speed():
    # massless cantilever, flat section; tip stiffness condensed over the free tip rotations
    L, W = 0.4, 100.0
    r = rectangular(0.03, 0.015)
    sec = general_section(r.area, r.Iy, r.Iz, r.torsion_constant)  # shear rigid: 3 EI / L^3
    t = beam_term((0, 1), L, sec, Material(2.1e11, 0.0, nu=0.3), Z, Z, 1, W, y_axis=[1, 0, 0])
    assert sorted(t.K) == [-2, 0, 2]
    kx, ky = 3 * 2.1e11 * sec.Iz / L**3, 3 * 2.1e11 * sec.Iy / L**3  # body x = section y
    km, kd = (kx + ky) / 2, (kx - ky) / 2
    for time in np.linspace(0.0, 0.05, 6):
        Kt = sum(np.real(v * np.exp(1j * k * W * time)) for k, v in t.K.items())[6:, 6:]
        a, b = [0, 1], [3, 4]
        Kc = Kt[np.ix_(a, a)] - Kt[np.ix_(a, b)] @ np.linalg.solve(
            Kt[np.ix_(b, b)], Kt[np.ix_(b, a)]
        )
        c2, s2 = np.cos(2 * W * time), np.sin(2 * W * time)
        np.testing.assert_allclose(
            Kc, km * np.eye(2) + kd * np.array([[c2, s2], [s2, -c2]]), rtol=1e-9, atol=1e-9 * km
        )


def test_lumped_and_consistent_rotary_inertia_agree_on_a_fine_mesh():
    # independent check of the lumped option: converges to the Timoshenko closed form
    L, sec = 0.5, hollow_circular(0.1, 0.06)
    exact = _timoshenko_ss(1, L, sec)
    for rotary, tol in (("consistent", 5e-5), ("lumped", 2e-4)):
        M, _, K = _dense(_shaft(40, L, sec, rotary=rotary), 6 * 41)
        dofs = [6 * i for i in range(1, 40)] + [6 * i + 4 for i in range(41)]
        w = np.sqrt(
            sla.eigh(
                K[np.ix_(dofs, dofs)].real,
                M[np.ix_(dofs, dofs)].real,
                eigvals_only=True,
                subset_by_index=[0, 0],
            )
        )[0]
        assert w == pytest.approx(exact, rel=tol)


def test_section_closed_forms_and_bad_input():
    s = rectangular(0.04, 0.02)
    assert s.Iy == pytest.approx(0.04 * 0.02**3 / 12) and s.Iz == pytest.approx(0.02 * 0.04**3 / 12)
    h = hollow_circular(0.05, 0.03)
    assert h.torsion_constant == pytest.approx(np.pi * (0.05**4 - 0.03**4) / 32)
    with pytest.raises(ModelError, match="diameter"):
        solid_circular(-1.0)
    with pytest.raises(ModelError, match="exactly one"):
        Material(E=1.0, density=1.0)
    with pytest.raises(ModelError, match="consistent"):
        beam_local_matrices(1.0, s, STEEL, rotary="consistent")
    with pytest.raises(ModelError, match="parallel"):
        beam_term((0, 1), 1.0, h, STEEL, [1, 0, 0], Z, 1, 1.0)
    with pytest.raises(ModelError, match="length"):
        beam_term((0, 1), 0.0, h, STEEL, Z, Z, 1, 1.0)
