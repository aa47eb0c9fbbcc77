"""Campbell diagram against the closed-form gyroscopic split of an overhung disk.

A rigid disk (mass ``m``, transverse and polar inertia ``J_t``, ``J_p``) at the tip of a
massless Timoshenko cantilever of length ``L``, clamped through a bearing of stiffness ``k_b``
on every component. Tip flexibility for a tip force ``P`` and moment ``M`` in one bending
plane (deflection ``u``, slope ``theta``), with the clamp compliance ``1 / k_b`` in
translation and rotation::

    u     = P (L^3 / 3EI + L / kappa G A + 1/k_b + L^2/k_b) + M (L^2 / 2EI + L/k_b)
    theta = P (L^2 / 2EI + L/k_b)                            + M (L / EI + 1/k_b)

``K = F^-1``. Circular whirl ``u_x + i u_y = U e^{i w t}`` at spin ``W`` (gyroscopic moment
``J_p W`` times the tilt rate): forward whirl satisfies
``det([[k11 - m w^2, k12], [k12, k22 - J_t w^2 + J_p W w]]) = 0`` and backward whirl the same
with ``-J_p W w``: the forward frequencies rise with speed, the backward ones fall.
"""

from __future__ import annotations

import numpy as np
import pytest

from rheolin.mechanics import Model
from rheolin.mechanics.sections import solid_circular
from rheolin.stability import campbell

E, NU, D, L, KB = 2.1e11, 0.3, 0.03, 0.25, 1e12
M, JT, JP = 8.0, 0.04, 0.07


def _overhung() -> Model:
    model = Model()
    model.add_shaft(
        "rotor", [0.0, L], outer_diameter=D, elastic_modulus=E, poisson_ratio=NU, density=0.0
    )
    model.add_disk("rotor", 1, mass=M, inertia=(JT, JT, JP))
    model.add_bearing("clamp", "rotor", 0, KB, components=None)
    return model


def _tip_stiffness() -> np.ndarray:
    sec = solid_circular(D, NU)
    EI, GA = E * sec.Iy, E / (2 * (1 + NU)) * sec.kappa_y * sec.area
    F = np.array(
        [
            [L**3 / (3 * EI) + L / GA + 1 / KB + L**2 / KB, L**2 / (2 * EI) + L / KB],
            [L**2 / (2 * EI) + L / KB, L / EI + 1 / KB],
        ]
    )
    return np.linalg.inv(F)


def _whirl_frequencies(W: float, sign: int) -> np.ndarray:
    """Positive roots of the forward (sign=+1) / backward (-1) characteristic quartic."""
    (k11, k12), (_, k22) = _tip_stiffness()
    # (k11 - m w^2)(k22 - Jt w^2 + s Jp W w) - k12^2
    poly = np.polymul([-M, 0.0, k11], [-JT, sign * JP * W, k22])
    poly = np.polysub(poly, [k12**2])
    r = np.roots(poly)
    return np.sort(r.real[(np.abs(r.imag) < 1e-9 * np.abs(r)) & (r.real > 0)])


def test_forward_and_backward_whirl_against_gyroscopic_split() -> None:
    speeds = np.array([50.0, 500.0, 1500.0, 3000.0])
    res = campbell(_overhung(), speeds)
    for i, W in enumerate(speeds):
        labels = res.whirl[i]
        for sign, kind in ((+1, "forward"), (-1, "backward")):
            got = np.sort(res.frequency[i][labels == kind])
            ref = _whirl_frequencies(W, sign)
            assert got.size == 2, (W, kind, res.frequency[i], labels)
            np.testing.assert_allclose(got, ref, rtol=1e-8)
        # axial and torsional modes of the disk on the shaft: no whirl
        assert set(labels[(labels != "forward") & (labels != "backward")]) <= {"none"}
    # the gyroscopic split grows with speed: forward up, backward down
    fwd = [np.sort(res.frequency[i][res.whirl[i] == "forward"])[1] for i in range(4)]
    bwd = [np.sort(res.frequency[i][res.whirl[i] == "backward"])[1] for i in range(4)]
    assert np.all(np.diff(fwd) > 0) and np.all(np.diff(bwd) < 0)
    assert np.allclose(res.damping_ratio[np.isfinite(res.damping_ratio)], 0.0, atol=1e-9)


def test_critical_speeds_are_order_line_crossings() -> None:
    """The 1x forward crossing solves the forward quartic with ``w = W``:
    ``(k11 - m W^2)(k22 - (J_t - J_p) W^2) = k12^2``."""
    (k11, k12), (_, k22) = _tip_stiffness()
    x = np.roots(np.polysub(np.polymul([-M, k11], [JP - JT, k22]), [k12**2]))
    ref = np.sqrt(x.real[(x.real > 0) & (np.abs(x.imag) < 1e-9)])
    speeds = np.linspace(0.8, 1.2, 9) * ref.min()
    res = campbell(_overhung(), speeds)
    crit = [c for c in res.critical_speeds if c.order == "1x rotor" and c.whirl == "forward"]
    assert len(crit) == 1
    # linear interpolation between samples 5 % apart: second-order error
    assert crit[0].speed == pytest.approx(ref.min(), rel=2e-3)
    ds = res.to_dataset()
    assert "critical_speed" in ds and ds.sizes["speed"] == speeds.size


def test_standstill_modes_are_the_non_spinning_closed_form() -> None:
    """W = 0 is allowed: forward and backward whirl coincide there, each lateral frequency
    twice, the roots of the quartic without the gyroscopic term; the CLI takes 0:...rpm."""
    res = campbell(_overhung(), np.array([0.0, 500.0]))
    assert res.speeds[0] == 0.0
    f0 = res.frequency[0][np.isfinite(res.frequency[0])]
    for ref in _whirl_frequencies(0.0, +1):
        assert np.sum(np.abs(f0 / ref - 1) < 1e-8) == 2, (ref, f0)
    with pytest.raises(ValueError, match=">= 0"):
        campbell(_overhung(), np.array([-1.0, 500.0]))
    from rheolin.cli.parse import parse_speeds

    assert parse_speeds("0:1000:500rpm", allow_zero=True)[0] == 0.0


# --------------------------------------------------------------------------- labels, tracking
def _two_disk_rotor() -> Model:
    """Friswell et al. (2010) Example 5.9.1 (ROSS's rotor_example): a 1.5 m steel shaft of
    50 mm, disks of 280 and 350 mm x 70 mm at 0.5 and 1.0 m, isotropic 1 MN/m bearings at
    the ends (undamped)."""
    m = Model()
    m.add_shaft("rotor", np.linspace(0.0, 1.5, 7), outer_diameter=0.05, elastic_modulus=211e9,
                density=7810.0, shear_modulus=81.2e9)  # fmt: skip
    for node, d in ((2, 0.28), (4, 0.35)):
        m.add_disk("rotor", node, outer_diameter=d, width=0.07, density=7810.0)
    for node in (0, 6):
        m.add_bearing(f"b{node}", "rotor", node, stiffness=1e6)
    return m


def test_two_disk_rotor_modes_labelled_and_tracked_across_speed() -> None:
    """0-10,000 rpm: each tracked lateral branch keeps one whirl direction (exactly +-1 on
    this isotropic rotor) and changes its frequency smoothly, although sorting by frequency
    swaps forward and backward branches where they cross; the modes labelled torsional and
    axial are those of the torsion-only and axial-only eigenproblems (phiz and uz DOFs of
    M_0, K_0 alone: uncoupled from bending on an axisymmetric rotor)."""
    import scipy.linalg as sla

    model = _two_disk_rotor()
    W = np.linspace(0.0, 10000.0, 51) * np.pi / 30
    r = campbell(model, W)
    assert r.tracked and r.kind is not None
    spinning = W > 0
    lateral = [j for j in range(r.frequency.shape[1]) if str(r.kind[1, j]).startswith("lateral ")]
    assert len(lateral) >= 6
    for j in lateral[:6]:
        signs = np.sign(r.whirl_ratio[spinning, j])
        assert np.all(signs == signs[0]), (j, r.kind[:, j])
        assert np.all(np.abs(np.abs(r.whirl_ratio[spinning, j]) - 1) < 1e-6)
        f = r.frequency[:, j]
        assert np.all(np.abs(np.diff(f)) < 0.1 * f[1:]), j
    for j in range(12):  # every tracked branch keeps its kind (torsional crossed by bending)
        assert len(set(r.kind[spinning, j].tolist())) == 1, (j, set(r.kind[spinning, j]))
    plain = campbell(model, W, track=False)
    swaps = [j for j in range(12) if len(set(plain.kind[spinning, j].tolist())) > 1]
    assert len(swaps) >= 4  # sorted branches swap: the tracking above is not trivially true
    # torsional and axial labels against the uncoupled eigenproblems
    a = model.assemble(3000 * np.pi / 30)
    K, M = a.system.K[0].toarray(), a.system.M[0].toarray()
    i = W.searchsorted(3000 * np.pi / 30)
    for comp, kind in (("phiz", "torsional"), ("uz", "axial")):
        dofs = [k for k, lab in enumerate(a.dof_labels) if lab[2] == comp]
        lam = sla.eigh(K[np.ix_(dofs, dofs)], M[np.ix_(dofs, dofs)], eigvals_only=True)
        ref = np.sqrt(lam[lam > 1e-6 * lam.max()])  # the free rigid motion excluded
        got = np.sort(r.frequency[i][r.kind[i] == kind])
        assert got.size == ref.size, (kind, got, ref)
        assert np.allclose(got, ref, rtol=1e-8)


# --------------------------------------------------------------------------- critical-speed map
def test_critical_speed_map_of_a_rigid_rotor_is_the_closed_form() -> None:
    """A rigid rotor (m, I_d, I_p) on one bearing: the translation critical speed follows
    ``sqrt(k / m)`` as the map varies k; the tilt, held by the bearing's fixed rotational
    stiffness k_t, stays at the forward synchronous ``sqrt(k_t / (I_d - I_p))``."""
    from rheolin.stability.critical_map import critical_speed_map

    mass, Id, Ip, kt = 20.0, 0.5, 0.2, 4e5
    m = Model()
    m.add_rigid_body("rotor", (0, 0, 0), mass, (Id, Id, Ip))
    m.add_bearing("b", "rotor", 0, [1e6, 1e6, 1e6, kt, kt, 0.0], components=None)
    k = np.logspace(4, 8, 5)
    r = critical_speed_map(m, k)
    tilt = np.sqrt(kt / (Id - Ip))
    for i, ki in enumerate(k):
        ref = np.sort([np.sqrt(ki / mass), tilt])
        np.testing.assert_allclose(r.speeds[i, :2], ref, rtol=1e-10)
        assert np.isnan(r.speeds[i, 2])  # nothing else whirls forward (torsion is free)
    assert r.actual == {"b": 1e6}
    # an axial/torsional support beside it is not a transverse bearing: not varied (giving
    # it the map's transverse stiffness would add a second support and change the closed form)
    m.add_bearing("thrust", "rotor", 0, [1e7, 1e3], components=["uz", "phiz"])
    again = critical_speed_map(m, k)
    assert again.bearings == ["b"]
    for i, ki in enumerate(k):
        ref = np.sort([np.sqrt(ki / mass), tilt])
        np.testing.assert_allclose(again.speeds[i, :2], ref, rtol=1e-10)


def test_critical_speed_map_limits_and_the_campbell_crossings() -> None:
    """The two-disk rotor: at its own bearing stiffness the map's critical speeds are the
    Campbell diagram's forward 1x crossings (modes over a speed grid, interpolated: another
    computation); a plain steel shaft on ever stiffer bearings tends to the pinned-pinned
    Euler-Bernoulli critical speed (pi / L)^2 sqrt(EI / rho A) (Timoshenko: slightly below)."""
    from rheolin.stability.critical_map import critical_speed_map

    model = _two_disk_rotor()
    r = critical_speed_map(model, [1e6])
    W = np.linspace(500.0, 3500.0, 301) * np.pi / 30
    camp = campbell(model, W)
    fwd = sorted(
        c.speed for c in camp.critical_speeds if c.order == "1x rotor" and c.whirl == "forward"
    )
    assert len(fwd) == 2
    np.testing.assert_allclose(r.speeds[0, :2], fwd, rtol=2e-4)
    stiff = critical_speed_map(_plain_shaft(21, 1e6), [1e11]).speeds[0, 0]
    assert 0.995 * PINNED[0] < stiff < PINNED[0]


#: A plain steel shaft (length, diameter, modulus, density) and its pinned-pinned
#: Euler-Bernoulli critical speeds (j pi / L)^2 sqrt(EI / rho A), j = 1..4.
L_S, D_S, E_S, RHO_S = 1.0, 0.02, 210e9, 7850.0
PINNED = (np.arange(1, 5) * np.pi / L_S) ** 2 * np.sqrt(
    E_S * (np.pi * D_S**4 / 64) / (RHO_S * np.pi * D_S * D_S / 4)
)


def _plain_shaft(nodes: int, k: float) -> Model:
    shaft = Model()
    shaft.add_shaft("s", np.linspace(0.0, L_S, nodes), outer_diameter=D_S, elastic_modulus=E_S,
                    density=RHO_S, poisson_ratio=0.3)  # fmt: skip
    for node in (0, nodes - 1):
        shaft.add_bearing(f"b{node}", "s", node, stiffness=k)
    return shaft


def test_fine_shaft_criticals_tend_to_the_pinned_pinned_beam() -> None:
    """The plain shaft at 401 nodes (2,406 DOF: the critical speeds by shift-invert Arnoldi)
    on stiff bearings: its first four critical speeds lie just below the pinned-pinned
    Euler-Bernoulli values (shear and rotary inertia lower them, more for higher ``j``)."""
    from rheolin.stability.critical_map import synchronous_critical_speeds

    ratio = synchronous_critical_speeds(_plain_shaft(401, 1e11), 4) / PINNED
    j = np.arange(1, 5)
    assert np.all(ratio < 1.0) and np.all(ratio > 1.0 - 5e-4 * j**2), ratio
    assert np.all(np.diff(ratio) < 0), ratio


def test_critical_speed_map_refuses_speed_dependent_bearings() -> None:
    from rheolin.errors import ModelError
    from rheolin.stability.critical_map import critical_speed_map

    m = Model()
    m.add_shaft("s", [0.0, 0.5], outer_diameter=0.05, material="steel")
    m.add_bearing("a", "s", 0, 1e7)
    m.add_bearing("t", "s", 1, stiffness=[1e7, 2e7], damping=[1.0, 2.0], speeds=[100.0, 300.0],
                  interpolation="linear")  # fmt: skip
    with pytest.raises(ModelError, match=r"\['t'\] have speed-dependent coefficients"):
        critical_speed_map(m, [1e6])
