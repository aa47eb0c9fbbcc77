"""The preloaded operating point (rheolin.mechanics.preload) against closed forms, SciPy special
functions, an independent scalar root and a transient (BDF) simulation of the nonlinear
equations.

* A rigid shaft on two Hertzian ball bearings under gravity: reactions by the lever rule,
  operating stiffness ``dF/d delta`` of the law at the lever-rule load, and the bounce/pitch
  natural frequencies of a rigid rotor on two springs of that stiffness.
* Many balls (Harris' element model) against Stribeck's integral ``J_r(1/2)`` (gamma
  functions).
* A torque-loaded gear pair with ISO 6336's load-dependent mesh stiffness: the reaction
  torque by the gear ratio, the static mesh deflection ``F / k(F)`` in closed form, and the
  torsional frequency with the tangent stiffness.
* A bearing with clearance beside a spring: contact opens and closes at ``k_s c``; the
  engaged deflection from ``brentq``.
* BDF on the nonlinear equations: started at the operating point the system stays at rest,
  and its small-amplitude response matches the frequency-domain solve of the linearized model.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import gamma

import rheolin as rl
from rheolin.errors import ModelError
from rheolin.mechanics.model import Model
from rheolin.results.outputs import bearing_force_array

G = 9.81
HERTZ = 2e10  # N/m^1.5, a lumped ball-bearing law F = K delta^1.5


def _rigid_shaft(law_a: dict, law_b: dict, mass: float = 20.0, J: float = 0.15) -> Model:
    """A rigid rotor: a disk (mass, transverse inertia J) at z = 0.15 m, rigidly linked
    (exactly: eliminated DOFs) to nearly massless journals at z = 0 and 0.5 m on two rolling
    bearings; an axial/torsional support; gravity -y."""
    m = Model()
    m.add_rigid_body("d", (0, 0, 0.15), mass, (J, J, 0.3))
    for name, z in (("ja", 0.0), ("jb", 0.5)):
        m.add_rigid_body(name, (0, 0, z), 1e-12, (1e-15, 1e-15, 1e-15))
        m.add_rigid_link(f"link_{name}", "d", 0, name, 0)
    m.add_rolling_bearing("A", "ja", 0, **law_a)
    m.add_rolling_bearing("B", "jb", 0, **law_b)
    m.add_bearing("thrust", "d", 0, stiffness=[1e9, 1e9], components=["uz", "phiz"])
    m.set_gravity((0.0, -G, 0.0))
    return m


def _frequencies(system: rl.PeriodicSystem) -> np.ndarray:
    """Undamped natural frequencies [rad/s] of a time-invariant system (rigid links
    eliminated; massless DOFs' infinite eigenvalues dropped)."""
    if system.constraint is not None:
        system = system.constraint.reduce(system)
    K = system.K[0].toarray()
    M = system.M[0].toarray()
    lam = sla.eigvals(K, M)
    lam = lam[np.isfinite(lam)].real
    return np.sort(np.sqrt(np.abs(lam)))


def test_two_hertzian_bearings_under_gravity_follow_the_lever_rule() -> None:
    law = dict(law="radial", kind="ball", stiffness=HERTZ)
    mass, J = 20.0, 0.15
    m = _rigid_shaft(law, law, mass, J)
    op = m.operating_point(1e-3)
    W = mass * G
    a, b = 0.15, 0.35  # disk from A and from B
    RA, RB = W * b / (a + b), W * a / (a + b)  # lever rule
    assert op.bearings["A"].force == pytest.approx([0.0, -RA, 0.0], abs=1e-8 * W)
    assert op.bearings["B"].force == pytest.approx([0.0, -RB, 0.0], abs=1e-8 * W)
    # operating stiffness = dF/d delta of the law at the deflection the load gives
    k = {}
    for name, R in (("A", RA), ("B", RB)):
        delta = (R / HERTZ) ** (2 / 3)
        assert op.bearings[name].deflection[1] == pytest.approx(-delta, rel=1e-9)
        kt, ks = 1.5 * HERTZ * delta**0.5, HERTZ * delta**0.5  # tangent and (across) secant
        K = op.bearings[name].stiffness
        assert K[1, 1] == pytest.approx(kt, rel=1e-9)
        assert K[0, 0] == pytest.approx(ks, rel=1e-9)
        k[name] = (kt, ks)
    # bounce and pitch of a rigid rotor on two springs (vertical: tangent, horizontal: secant)
    system = m.assemble(1e-3).system
    got = _frequencies(system)
    expected = []
    for i in (0, 1):
        kA, kB = k["A"][i], k["B"][i]
        Kc = np.array([[kA + kB, kB * b - kA * a], [kB * b - kA * a, kA * a * a + kB * b * b]])
        expected += list(np.sqrt(sla.eigvalsh(Kc, np.diag([mass, J]))))
    for w in expected:
        assert np.min(np.abs(got - w)) <= 1e-6 * w
    # the linearized model's static response is the equilibrium, with the bearing loads
    sol = rl.solve(system, [0])
    assert sol.success
    a0 = m.assemble(1e-3)
    q0 = np.real(sol.q[list(sol.harmonics).index(0)])
    assert np.abs(q0 - op.displacement).max() <= 1e-9 * np.abs(op.displacement).max()
    h, F = bearing_force_array(sol, a0, "A")
    assert np.real(F[list(h).index(0), :3]) == pytest.approx(op.bearings["A"].force, abs=1e-8 * W)


def test_many_balls_match_stribecks_integral() -> None:
    """Z balls without clearance under a radial load F: ``F = Z K_n delta^n J_r(1/2)`` with
    ``J_r(1/2) = Gamma((n + 2)/2) / (2 sqrt(pi) Gamma((n + 3)/2))`` (0.2288 for balls)."""
    n, Z, Kn, mass = 1.5, 720, 5e9, 30.0
    law = dict(law="elements", kind="ball", stiffness=Kn, elements=Z, angle=np.pi / Z)
    m = _rigid_shaft(law, dict(law="radial", kind="ball", stiffness=HERTZ), mass)
    op = m.operating_point(1e-3)
    R = mass * G * 0.35 / 0.5
    J = gamma((n + 2) / 2) / (2 * np.sqrt(np.pi) * gamma((n + 3) / 2))
    assert J == pytest.approx(0.2288, abs=1e-4)
    delta = (R / (Z * Kn * J)) ** (1 / n)
    assert -op.bearings["A"].deflection[1] == pytest.approx(delta, rel=1e-5)
    assert op.bearings["A"].in_contact == Z // 2


@pytest.mark.parametrize("torque", [5.0, 40.0])
def test_gear_pair_mesh_stiffness_under_torque(torque: float) -> None:
    """ISO 6336's reduction ``k = k0 (F / F_ref)^(1/4)`` below ``F_ref = b 100 N/mm``."""
    z1, z2, mod, alpha, b, k0 = 20, 50, 0.004, np.radians(20.0), 0.02, 4e8
    J1, J2, k_lat = 2e-3, 0.05, 1e12
    m = Model()  # gears held on stiff supports, their translations nearly massless
    m.add_rigid_body("p", (0, 0, 0), 1e-6, (J1 / 2, J1 / 2, J1))  # thin disks
    m.add_rigid_body("g", (mod * (z1 + z2) / 2, 0, 0), 1e-6, (J2 / 2, J2 / 2, J2))
    for body in ("p", "g"):
        m.add_bearing(f"{body}_b", body, 0, stiffness=k_lat,
                      components=["ux", "uy", "uz", "phix", "phiy"])  # fmt: skip
    m.add_gear_mesh("mesh", "p", 0, "g", 0, z1, z2, mod, pressure_angle=alpha, stiffness=k0,
                    load_law="iso6336", face_width=b)  # fmt: skip
    m.add_torque("input", "p", 0, torque)
    m.add_torque("load", "g", 0, "reaction")
    op = m.operating_point(10.0)
    rb1, rb2 = mod * z1 / 2 * np.cos(alpha), mod * z2 / 2 * np.cos(alpha)
    F = torque / rb1
    # no net power on the free rotation: T_in w_p + T_load w_g = 0, w_g = -w_p z1 / z2
    assert op.torques["load"] == pytest.approx(torque * z2 / z1, rel=1e-9)
    ms = op.meshes["mesh"]
    assert abs(ms.force) == pytest.approx(F, rel=1e-9)
    Fref = b * 1e5
    assert F < Fref
    k_F = k0 * (F / Fref) ** 0.25
    assert abs(ms.deflection) == pytest.approx(F / k_F, rel=1e-9)  # F / k(F)
    assert ms.stiffness == pytest.approx(4 / 3 * k_F, rel=1e-9)
    # torsional mode of the pair on the tangent stiffness, in series with the two supports
    # along the line of action (the nearly massless translations follow quasi-statically)
    got = _frequencies(m.assemble(10.0).system)

    def torsional(k: float) -> float:
        return float(np.sqrt((1 / (1 / k + 2 / k_lat)) * (rb1**2 / J1 + rb2**2 / J2)))

    w = torsional(ms.stiffness)
    assert np.min(np.abs(got - w)) <= 1e-8 * w
    # the shift from the nominal stiffness k0, as the law predicts
    assert w / torsional(k0) == pytest.approx(
        torsional(4 / 3 * k0 * (F / Fref) ** 0.25) / torsional(k0), rel=1e-9
    )


def _clearance_model(W: float, ks: float, c: float) -> Model:
    m = Model()
    m.add_rigid_body("r", (0, 0, 0), 1.0, (1e-3, 1e-3, 2e-3))
    m.add_bearing("spring", "r", 0, stiffness=[ks, ks, 1e9, 1e6, 1e6, 1e6], components=None)
    m.add_rolling_bearing("gap", "r", 0, law="radial", kind="roller", stiffness=HERTZ,
                          clearance=c)  # fmt: skip
    m.add_force("load", "r", 0, force=(0.0, -W, 0.0))
    return m


def test_clearance_opens_and_closes_at_the_predicted_load() -> None:
    ks, c = 2e6, 30e-6
    Wc = ks * c  # the spring alone closes the gap at this load
    below = _clearance_model(0.99 * Wc, ks, c).operating_point(1.0)
    assert below.bearings["gap"].in_contact == 0 and below.bearings["gap"].load == 0.0
    assert -below.node_displacement("r", 0)[1] == pytest.approx(0.99 * Wc / ks, rel=1e-12)
    for W in (1.01 * Wc, 3 * Wc):
        op = _clearance_model(W, ks, c).operating_point(1.0)
        n = 10 / 9
        d = brentq(lambda x, W=W, n=n: ks * x + HERTZ * max(x - c, 0.0) ** n - W, 0.0,
                   W / ks, xtol=1e-22, rtol=1e-15)  # fmt: skip
        assert op.bearings["gap"].in_contact == 1
        assert -op.node_displacement("r", 0)[1] == pytest.approx(d, rel=1e-9)
        assert op.bearings["gap"].load == pytest.approx(HERTZ * (d - c) ** n, rel=1e-8)


def test_bdf_stays_at_the_operating_point_and_matches_the_linearized_response() -> None:
    """A rotor node on a Hertzian bearing and a soft spring under gravity. Started at the
    operating point, BDF on the nonlinear equations stays there; a small harmonic force then
    gives the response the frequency domain predicts on the linearized model."""
    mass, ks, c_d, Kh = 2.0, 1e5, 60.0, 1e9
    eps, Om = 0.02, 900.0  # N, rad/s

    def model(excite: bool) -> Model:
        m = Model()
        m.add_rigid_body("r", (0, 0, 0), mass, (1e-3, 1e-3, 2e-3))
        m.add_bearing("spring", "r", 0, stiffness=[ks, ks, 1e7, 1e4, 1e4, 1e4],
                      damping=[c_d, c_d, 10.0, 1.0, 1.0, 1.0], components=None)  # fmt: skip
        m.add_rolling_bearing("hz", "r", 0, law="radial", kind="ball", stiffness=Kh)
        m.set_gravity((0.0, -G, 0.0))
        if excite:
            m.add_force("shaker", "r", 0, force=(eps, 0.0, 0.0), order=1)
        return m

    op = model(False).operating_point(Om)
    x0, y0 = op.node_displacement("r", 0)[:2]
    assert x0 == pytest.approx(0.0, abs=1e-15) and y0 < 0

    def rhs(t: float, s: np.ndarray, force: float) -> np.ndarray:
        x, y, vx, vy = s
        r = np.hypot(x, y)
        f = Kh * r**1.5
        fx, fy = (-f * x / r, -f * y / r) if r > 0 else (0.0, 0.0)
        ax = (fx - ks * x - c_d * vx + force * np.cos(Om * t)) / mass
        ay = (fy - ks * y - c_d * vy - mass * G) / mass
        return np.array([vx, vy, ax, ay])

    with np.errstate(under="ignore"):
        rest = solve_ivp(rhs, (0, 0.2), [x0, y0, 0, 0], method="BDF", args=(0.0,),
                         rtol=1e-12, atol=1e-16)  # fmt: skip
    assert rest.success
    assert np.abs(rest.y[0]).max() <= 1e-12 and np.abs(rest.y[1] - y0).max() <= 1e-9 * abs(y0)
    # small-amplitude response: transient decays (zeta ~ 0.03), then one period is projected
    periods = 400
    Tp = 2 * np.pi / Om
    t_end = periods * Tp
    t_eval = np.linspace(t_end - Tp, t_end, 257)[:-1]
    with np.errstate(under="ignore"):
        run = solve_ivp(rhs, (0, t_end), [x0, y0, 0, 0], method="BDF", args=(eps,),
                        rtol=1e-10, atol=1e-14, t_eval=t_eval)  # fmt: skip
    assert run.success
    x1 = 2 * np.mean(run.y[0] * np.exp(-1j * Om * t_eval))  # complex amplitude of x at Om
    exc = model(True)
    a = exc.assemble(Om)
    sol = rl.solve(a.system, [0, 1])
    assert sol.success
    q1 = 2 * sol.q[list(sol.harmonics).index(1)][a.dofs("r", 0)[0]]
    assert abs(x1 - q1) <= 2e-5 * abs(q1)  # measured 2.6e-6: second-order terms in eps
    q0 = np.real(sol.q[list(sol.harmonics).index(0)][a.dofs("r", 0)[1]])
    assert q0 == pytest.approx(y0, rel=1e-9)


def test_failures_name_the_joint() -> None:
    # a bearing whose table saturates below the load: no equilibrium
    m = Model()
    m.add_rigid_body("r", (0, 0, 0), 1.0, (1e-3, 1e-3, 2e-3))
    m.add_bearing("axial", "r", 0, stiffness=[1e8, 1e6, 1e6, 1e6],
                  components=["uz", "phix", "phiy", "phiz"])  # fmt: skip
    m.add_rolling_bearing("weak", "r", 0, law="table", deflection=[0, 1e-5, 2e-5, 3e-5],
                          force=[0, 40.0, 50.0, 50.0])  # fmt: skip
    m.add_force("load", "r", 0, force=(0.0, -200.0, 0.0))
    with pytest.raises(ModelError, match="'weak'"):
        m.operating_point(1.0)
    # a reaction torque with nothing to balance
    m = Model()
    m.add_rigid_body("r", (0, 0, 0), 1.0, (1e-3, 1e-3, 2e-3))
    m.add_bearing("all", "r", 0, stiffness=1e8, components=None)
    m.add_torque("load", "r", 0, "reaction")
    with pytest.raises(ModelError, match=r"'load'.*no free rotation"):
        m.operating_point(1.0)
    with pytest.raises(ModelError, match="`torque`"):
        m.add_torque("bad", "r", 0, "lots")
    with pytest.raises(ModelError, match="`elements`"):
        m.add_rolling_bearing("z2", "r", 0, law="elements", stiffness=1e9, elements=2)
    with pytest.raises(ModelError, match="`deflection`"):
        m.add_rolling_bearing("t", "r", 0, law="table", deflection=[1e-6, 0], force=[0, 1])


def test_preload_of_a_linear_joint() -> None:
    """``preload + K delta``: a mass on a spring preloaded by p under a load W deflects by
    (W - p) / k, and the reported bearing force is W."""
    k, p, W = 1e6, 30.0, 100.0
    m = Model()
    m.add_rigid_body("r", (0, 0, 0), 1.0, (1e-3, 1e-3, 2e-3))
    m.add_bearing("s", "r", 0, stiffness=[k, k, k, 1e4, 1e4, 1e4], components=None,
                  preload=[0.0, p, 0.0])  # fmt: skip
    m.add_force("w", "r", 0, force=(0.0, W, 0.0))
    a = m.assemble(1.0)
    sol = rl.solve(a.system, [0])
    q0 = np.real(sol.q[0])
    assert q0[1] == pytest.approx((W - p) / k, rel=1e-12)
    _, F = bearing_force_array(sol, a, "s")
    assert np.real(F[0, 1]) == pytest.approx(W, rel=1e-12)


def test_critical_speed_map_of_a_preloaded_model_uses_the_operating_stiffness() -> None:
    """The map's "model's own stiffness" of a rolling bearing is its operating stiffness, the
    mean of the vertical tangent and horizontal secant of the Hertz law at the lever-rule
    load; the map is that of the linearized model."""
    from rheolin.stability.critical_map import critical_speed_map

    law = dict(law="radial", kind="ball", stiffness=HERTZ)
    m = _rigid_shaft(law, law)
    cmap = critical_speed_map(m, [1e6, 1e7])
    R = 20.0 * G * 0.35 / 0.5
    delta = (R / HERTZ) ** (2 / 3)
    assert cmap.actual["A"] == pytest.approx((1.5 + 1.0) / 2 * HERTZ * delta**0.5, rel=1e-9)
    again = critical_speed_map(m.operating_point(1.0).model, [1e6, 1e7])
    assert np.allclose(cmap.speeds, again.speeds, equal_nan=True)


def test_a_rectangular_wave_mesh_is_scaled_to_its_operating_stiffness() -> None:
    """A mesh given by its single/double tooth-pair levels: the linearized model keeps the
    wave (both levels scaled), its mean is the tangent stiffness, and the relative ripple
    ``k_j / k_0`` is unchanged."""
    z1, z2, mod = 20, 50, 0.004
    m = Model()
    m.add_rigid_body("p", (0, 0, 0), 0.5, (1e-3, 1e-3, 2e-3))
    m.add_rigid_body("g", (mod * (z1 + z2) / 2, 0, 0), 3.0, (0.025, 0.025, 0.05))
    for body in ("p", "g"):
        m.add_bearing(f"{body}_b", body, 0, stiffness=1e10,
                      components=["ux", "uy", "uz", "phix", "phiy"])  # fmt: skip
    m.add_gear_mesh("mesh", "p", 0, "g", 0, z1, z2, mod, contact_ratio=1.6,
                    single_stiffness=3e8, double_stiffness=5e8, load_law="table",
                    load_forces=[0.0, 500.0, 2000.0], load_stiffness=[2e8, 3e8, 4.2e8])  # fmt: skip
    m.add_torque("input", "p", 0, 15.0)
    m.add_torque("load", "g", 0, "reaction")
    op = m.operating_point(10.0)
    before, after = m.meshes["mesh"]["stiffness"], op.model.meshes["mesh"]["stiffness"]
    ms = op.meshes["mesh"]
    assert np.real(after[0]) == pytest.approx(ms.stiffness, rel=1e-12)
    assert ms.nominal == pytest.approx(np.real(before[0]), rel=1e-12)
    for j in (1, 2, 3):
        assert after[j] / after[0] == pytest.approx(before[j] / before[0], rel=1e-12)
