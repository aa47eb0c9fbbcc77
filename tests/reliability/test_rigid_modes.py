"""Rigid-body modes (free motion with mass) are found and held, not solved into a singular
harmonic 0 or a false Floquet instability: against the relative-coordinate equation of a
free two-inertia drive (time integration, monodromy), the free-free chain's closed-form
frequencies, and ROSS's unbalance response of its own rotor with free axial and torsion."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import rheolin as rl
from rheolin.system.rigid_modes import find_rigid_modes

J1, J2, K0, EPS, C, W = 2.0, 3.0, 4.0e4, 0.3, 6.0, 90.0
T_MEAN, T_DYN = 5.0, 2.0  # on inertia 1: a mean torque (taken by the drive) and a 1x one


def _two_inertia() -> rl.PeriodicSystem:
    """Two inertias coupled by a mesh stiffness ``K0 (1 + EPS cos W t)`` and a damper, no
    drive stiffness: the torsion of the pair is free."""
    S = np.array([[1.0, -1.0], [-1.0, 1.0]])
    return rl.PeriodicSystem(
        W,
        M={0: np.diag([J1, J2])},
        D={0: C * S},
        K={0: K0 * S, 1: 0.5 * EPS * K0 * S},
        f={0: np.array([T_MEAN, 0.0]), 1: np.array([0.5 * T_DYN, 0.0])},
    )


def _relative(t, y):
    """``Je x'' + C x' + K0 (1 + EPS cos W t) x = J2 T1(t) / (J1 + J2)``, ``x = th1 - th2``:
    the free pair held at ``J1 th1 + J2 th2 = 0`` (the drive takes the mean motion)."""
    je = J1 * J2 / (J1 + J2)
    torque = J2 * (T_MEAN + T_DYN * np.cos(W * t)) / (J1 + J2)
    x, v = y
    return [v, (torque - C * v - K0 * (1 + EPS * np.cos(W * t)) * x) / je]


def test_free_two_inertia_drive_is_held_and_matches_its_relative_coordinate():
    s = _two_inertia()
    rigid = find_rigid_modes(s)
    assert rigid is not None and rigid.count == 1
    assert np.allclose(rigid.modes[:, 0], 1 / np.sqrt(J1 + J2), rtol=1e-12)
    sol = rl.solve(s, 14)
    assert sol.success and sol.info["rigid_modes"] == 1, sol.message
    assert "rigid-body mode" in sol.message
    # the constraint takes the mean torque: R^T f_0
    assert np.isclose(sol.info["rigid_mean_load"][0], T_MEAN / np.sqrt(J1 + J2), rtol=1e-12)
    period = 2 * np.pi / W
    decay = (J1 * J2 / (J1 + J2)) / C * 2  # 1 / (C / 2 Je)
    t_end = np.ceil(40 * decay / period) * period
    t = t_end + np.linspace(0, period, 41)
    ivp = solve_ivp(_relative, (0, t[-1]), [0, 0], method="DOP853", rtol=1e-11, atol=1e-16,
                    t_eval=t)  # fmt: skip
    x = ivp.y[0]
    q = sol.time_response(t) if hasattr(sol, "time_response") else None
    if q is None:
        E = np.exp(1j * np.outer(t, sol.harmonics) * W)
        q = np.real(E @ sol.q)
    assert np.abs((q[:, 0] - q[:, 1]) - x).max() < 1e-7 * np.abs(x).max()
    # the held motion: J1 th1 + J2 th2 = 0, so th1 = J2 x / (J1 + J2)
    assert np.abs(q[:, 0] - J2 * x / (J1 + J2)).max() < 1e-7 * np.abs(x).max()


def test_free_two_inertia_floquet_is_the_relative_coordinate_monodromy_not_a_false_pair():
    """Without the constraint the double zero exponent splits into +-sqrt(eps) by round-off,
    read as an instability. Held, the exponents are those of the relative coordinate."""
    res = rl.floquet(_two_inertia())
    assert res.info.get("rigid_modes") == 1 and "rigid-body mode" in res.info["note"]
    period = 2 * np.pi / W
    cols = []
    for y0 in ([1.0, 0.0], [0.0, 1.0]):
        out = solve_ivp(lambda t, y: np.subtract(_relative(t, y), _relative(t, [0, 0])),
                        (0, period), y0, method="DOP853", rtol=1e-12, atol=1e-14)  # fmt: skip
        cols.append(out.y[:, -1])
    mu = np.linalg.eigvals(np.column_stack(cols))
    expected = np.log(np.abs(mu)).max() / period
    assert res.stable and res.decided
    assert abs(res.max_real - expected) < 1e-6 * abs(expected), (res.max_real, expected)


def test_free_free_chain_keeps_its_closed_form_elastic_frequencies():
    """N equal masses and springs, both ends free: w_j = 2 sqrt(k/m) sin(j pi / 2N),
    j = 1..N-1, and the rigid translation (j = 0) held."""
    n, k, m = 12, 3.0e5, 1.5
    K = np.zeros((n, n))
    for i in range(n - 1):
        K[i : i + 2, i : i + 2] += k * np.array([[1, -1], [-1, 1]])
    beta = 1e-6  # proportional damping D = beta K: lambda = -beta w^2 / 2 +- i w sqrt(1 - z^2)
    s = rl.PeriodicSystem(2000.0, M={0: m * np.eye(n)}, D={0: beta * K}, K={0: K})
    res = rl.floquet(s)
    assert res.info["rigid_modes"] == 1
    lam = res.exponents[res.exponents.imag > 0]
    lam = lam[np.argsort(lam.imag)]
    w = 2 * np.sqrt(k / m) * np.sin(np.arange(1, n) * np.pi / (2 * n))
    zeta = beta * w / 2
    assert lam.size == n - 1
    assert np.allclose(lam.imag, w * np.sqrt(1 - zeta**2), rtol=1e-10)
    assert np.allclose(lam.real, -zeta * w, rtol=1e-8)
    assert res.stable and res.decided


def test_massless_free_dof_is_not_a_rigid_body():
    """A null vector without mass is a singular model: not held, left to the solver."""
    K = np.array([[2.0, -1.0, 0.0], [-1.0, 1.0, 0.0], [0.0, 0.0, 0.0]])
    s = rl.PeriodicSystem(5.0, M={0: np.diag([1.0, 1.0, 0.0])}, K={0: K},
                          f={1: np.array([1.0, 0.0, 0.0])})  # fmt: skip
    assert find_rigid_modes(s) is None


@pytest.fixture(scope="module")
def ross():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return pytest.importorskip("ross")


def test_ross_rotor_with_free_axial_and_torsion_and_an_unbalanced_disk_matches_ross(ross):
    """ROSS's rotor_example has no axial or torsional support. With an unbalance on its disk
    it used to fail at every speed ("singular at harmonic 0"); held, the lateral response
    equals ROSS's unbalance response (ROSS applies the unbalance as a force: the eccentric
    disk's own rheo-linear terms differ at second order in the eccentricity)."""
    from rheolin.io.ross import model_from_ross
    from rheolin.results.compute import solve_point

    rotor = ross.rotor_example()
    model = model_from_ross(rotor)
    node, u, phase = 2, 1e-4, 0.3
    model.add_disk(model.bodies and next(iter(model.bodies)), node, unbalance=u,
                   unbalance_angle=phase)  # fmt: skip
    speeds = np.array([150.0, 400.0, 700.0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        X = np.asarray(rotor.run_unbalance_response([node], [u], [phase], speeds).forced_resp)
    for i, w in enumerate(speeds):
        p = solve_point(model, float(w), order=2, stability=False)
        sol = p.solution
        assert sol.success and sol.info["rigid_modes"] >= 1, sol.message
        q1 = sol.q[list(sol.harmonics).index(1)]
        got = 2 * q1[6 * node : 6 * node + 2]
        want = X[6 * node : 6 * node + 2, i]
        assert np.abs(got - want).max() < 1e-9 * np.abs(want).max(), (w, got, want)


def test_large_sparse_free_chain_is_held_after_harmonic_0_reports_singular():
    """1,200 masses on springs, both ends free (sparse; found by shift-invert Lanczos once
    the factorization of K_0 reports harmonic 0 singular). A self-equilibrated load drives no
    rigid motion, so the held response equals the unconstrained one, which is regular at
    w != 0: a dense solve of K - w^2 M + i w D."""
    import scipy.sparse as sp

    from rheolin.system.rigid_modes import DENSE_LIMIT

    n, k, m, w = 1200, 2.0e6, 0.5, 700.0
    assert n > DENSE_LIMIT
    e = np.ones(n)
    K = sp.diags_array([-k * e[:-1], k * np.r_[1, 2 * e[1:-1], 1], -k * e[:-1]], offsets=[-1, 0, 1])
    M, D = sp.diags_array(m * e), 1e-5 * K
    f = np.zeros(n)
    f[0], f[-1] = 1.0, -1.0
    s = rl.PeriodicSystem(w, M={0: M.tocsc()}, D={0: D.tocsc()}, K={0: K.tocsc()}, f={1: f / 2})
    sol = rl.solve(s, 1, stability=False)
    assert sol.success and sol.info["rigid_modes"] == 1, sol.message
    A = (K - w**2 * M + 1j * w * D).toarray()
    want = np.linalg.solve(A, f / 2)
    got = sol.q[list(sol.harmonics).index(1)]
    assert np.abs(got - want).max() < 1e-9 * np.abs(want).max()
    assert np.abs(sol.q[list(sol.harmonics).index(0)]).max() == 0.0


def test_soft_springs_on_nearly_massless_nodes_are_not_free_motions() -> None:
    """A very stiff, nearly massless shaft (E x 100, density 1e-6) carrying a 20 kg disk on two
    soft springs: mass scaling had hidden the springs (they act on massless end nodes) and held
    the lateral translations as rigid-body modes, answering zero. The lateral unbalance
    response is the rigid-disk closed form ``U W^2 / (2 k - m W^2)``."""
    from rheolin.mechanics import Model
    from rheolin.results import solve_point

    m, k, U, W = 20.0, 1e5, 1e-4, 40.0
    model = Model()
    model.add_shaft("s", [0.0, 0.2, 0.4], outer_diameter=0.08, elastic_modulus=2.1e13,
                    density=1e-6, poisson_ratio=0.3)  # fmt: skip
    model.add_disk("s", 1, mass=m, inertia=[0.5, 0.5, 0.2], unbalance=U)
    for node in (0, 2):
        model.add_bearing(f"b{node}", "s", node, stiffness=k)
    p = solve_point(model, W, stability=False)
    assert p.solution.success, p.solution.message
    x = p.solution.harmonic(1)[p.assembled.dofs("s", 1)[0]]
    ref = U * W**2 / (2 * k - m * W**2)
    assert abs(2 * abs(x) - ref) < 1e-4 * ref  # the shaft's own compliance: 2k / 3e10 = 6e-6


@pytest.mark.parametrize("support", [1e12, 1e13])
def test_free_rotation_of_a_gear_pair_on_stiff_supports_with_light_hubs(support: float) -> None:
    """A spur pair (20:50, module 4 mm) whose hubs weigh 1e-6 kg on 1e12-1e13 N/m supports:
    its free rotation is found (it was missed: the inverse iteration's shift sat above the
    softest elastic mode), with the gear-ratio shape ``phi_g / phi_p = -z1 / z2``."""
    from rheolin.mechanics.model import Model

    z1, z2, mod = 20, 50, 0.004
    m = Model()
    m.add_rigid_body("p", (0, 0, 0), 1e-6, (1e-3, 1e-3, 2e-3))  # thin disks
    m.add_rigid_body("g", (mod * (z1 + z2) / 2, 0, 0), 1e-6, (0.025, 0.025, 0.05))
    for body in ("p", "g"):
        m.add_bearing(f"{body}_b", body, 0, stiffness=support,
                      components=["ux", "uy", "uz", "phix", "phiy"])  # fmt: skip
    m.add_gear_mesh("mesh", "p", 0, "g", 0, z1, z2, mod, stiffness=4.2e8)
    a = m.assemble(10.0)
    rigid = find_rigid_modes(a.system)
    assert rigid is not None and rigid.count == 1
    r = rigid.modes[:, 0]
    phi_p, phi_g = r[a.dofs("p", 0)[5]], r[a.dofs("g", 0)[5]]
    assert phi_g / phi_p == pytest.approx(-z1 / z2, rel=1e-9)


def _shaft_without(lateral: bool) -> rl.Model:
    """A steel shaft with a disk, on bearings that hold its axial and torsional motion only
    (``lateral=False``) or its lateral motion only (``lateral=True``)."""
    from rheolin.mechanics.model import Model

    m = Model()
    m.add_shaft("rotor", [0.0, 0.25, 0.5], outer_diameter=0.04, material="steel")
    m.add_disk("rotor", 1, mass=8.0, inertia=(0.05, 0.05, 0.1), unbalance=1e-4)
    comps = ["ux", "uy"] if lateral else ["uz", "phiz"]
    for node in (0, 2):
        m.add_bearing(f"b{node}", "rotor", node, stiffness=[1e7, 1e7], components=comps)
    return m


def test_a_shaft_nothing_holds_laterally_is_refused_naming_it_and_the_direction() -> None:
    """No steady state: refused by the solve and by the stability check, naming the body
    and its lateral (and tilting) motion; never held as a rigid-body mode."""
    from rheolin.system.rigid_modes import FreeBodyError

    system = _shaft_without(lateral=False).assemble(300.0).system
    with pytest.raises(FreeBodyError, match=r"body 'rotor' moves laterally and tilts \(ux, uy"):
        rl.solve(system, 2, stability=False)
    with pytest.raises(FreeBodyError, match="body 'rotor'"):
        rl.floquet(system)


def test_a_shaft_held_laterally_has_its_axial_and_torsional_motion_held() -> None:
    """The same shaft on lateral bearings only: its axial and torsional rigid motions are a
    drive train's, held; the lateral unbalance response is that of the supported shaft (the
    held motions do not couple into it: the lateral response with a stiff axial/torsional
    support added instead is the same)."""
    free = _shaft_without(lateral=True)
    held = _shaft_without(lateral=True)
    held.add_bearing("thrust", "rotor", 0, stiffness=[1e12, 1e12], components=["uz", "phiz"])
    W = 300.0
    a, b = free.assemble(W), held.assemble(W)
    s1, s2 = rl.solve(a.system, 2, stability=False), rl.solve(b.system, 2, stability=False)
    assert s1.success and s1.info["rigid_modes"] == 2, s1.message
    lat = [i for i, (_, _, c) in enumerate(a.dof_labels) if c in ("ux", "uy")]
    q1, q2 = s1.harmonic(1)[lat], s2.harmonic(1)[lat]
    assert np.allclose(q1, q2, rtol=1e-8, atol=1e-8 * np.abs(q2).max())


def test_a_system_built_by_hand_is_held_as_given() -> None:
    """Without the model's bodies (``system.motions`` is None) a rigid mode cannot be named:
    it is held, as docs/solvers.md says (the free-free chain above)."""
    s = _two_inertia()
    assert s.motions is None
    assert rl.solve(s, 3).info["rigid_modes"] == 1


def test_a_fine_mesh_whose_lowest_modes_are_all_soft_is_not_taken_for_rigid_bodies() -> None:
    """A 10 m shaft on 2,001 nodes (12,006 DOF) held laterally at both ends: its lowest
    bending modes (6.2 rad/s and up, ``(n pi / L)^2 sqrt(EI / rho A)``) lie below 1e-8 of its
    stiffest mass-scaled element, so every eigenvalue the Lanczos search returns is a
    candidate; exactly two are free motions, its axial translation and its torsion."""
    m = rl.Model()
    m.add_shaft("s", np.linspace(0.0, 10.0, 2001), outer_diameter=0.05, material="steel")
    for name, node in (("A", 0), ("B", 2000)):
        m.add_bearing(name, "s", node, stiffness=[1e8, 1e8], damping=[100.0, 100.0],
                      components=["ux", "uy"])  # fmt: skip
    system = m.assemble(100.0).system
    assert system.n == 12006
    found = find_rigid_modes(system)
    assert found is not None and found.count == 2
