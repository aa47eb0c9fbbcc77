"""The static equilibrium of a preloaded model is found wherever it exists (the globalized
Newton method of rheolin.mechanics.preload.newton), and refused only where it does not,
naming the joint or body and the load in N. References: the Hertzian element sums written
here, solved by SciPy's root finders (1-D ``brentq`` along a symmetry axis, 2-D ``root``);
the lever rule of a statically determinate rotor; ``T_in + T_out (-z1 / z2)`` for a torque
nothing balances."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq, root

import rheolin as rl
from rheolin.errors import ModelError

N_EXP = {"ball": 1.5, "roller": 10.0 / 9.0}
K_N = {"ball": 8e9, "roller": 1.5e9}


def _rotor(law: str = "elements", kind: str = "roller", Z: int = 10, c: float = 30e-6,
           load=(0.0, -1500.0, 0.0), angle: float = 0.0, **extra) -> rl.Model:  # fmt: skip
    """A rigid rotor (10 kg) held radially only by one rolling bearing; an axial and
    tilting support; a static force on its node."""
    m = rl.Model()
    m.add_rigid_body("r", (0, 0, 0), 10.0, (0.1, 0.1, 0.2))
    m.add_bearing("axial", "r", 0, stiffness=[1e8, 1e6, 1e6, 1e4],
                  components=["uz", "phix", "phiy", "phiz"])  # fmt: skip
    m.add_rolling_bearing("rol", "r", 0, law=law, kind=kind, stiffness=extra.pop("K", K_N[kind]),
                          elements=Z, clearance=c, angle=angle, **extra)  # fmt: skip
    m.add_force("w", "r", 0, force=load)
    return m


def _sums(kind: str, Z: int, c: float, angle: float):
    """The element sums of Harris' model, written out: ``F(d) = sum_i K <e_i.d - c>^n e_i``
    (the force the inner ring's elements push back with) and each element's load."""
    n, K = N_EXP[kind], K_N[kind]
    psi = angle + 2 * np.pi * np.arange(Z) / Z
    E = np.column_stack([np.cos(psi), np.sin(psi)])

    def loads(d: np.ndarray) -> np.ndarray:
        return K * np.maximum(E @ d - c, 0.0) ** n

    return (lambda d: E.T @ loads(d)), loads


@pytest.mark.parametrize("c", [20e-6, 30e-6, 40e-6])
def test_roller_bearing_with_clearance_carries_the_load_on_two_rollers(c: float) -> None:
    """The case once refused ("Newton stalled ... no rolling element in contact"): Z = 10
    rollers, 1.5 kN straight down between two rollers (252 and 288 deg). By symmetry the
    deflection is vertical; each of the two rollers carries ``1500 / (2 cos 18 deg)``."""
    op = _rotor(c=c).operating_point(1.0)
    d = op.bearings["rol"].deflection[:2]
    force, loads = _sums("roller", 10, c, 0.0)
    dy = brentq(lambda y: force(np.array([0.0, -y]))[1] + 1500.0, c, c + 1e-3, xtol=1e-16)
    assert d[1] == pytest.approx(-dy, rel=1e-8) and abs(d[0]) < 1e-12 * dy
    q = loads(d)
    assert np.count_nonzero(q) == 2 and op.bearings["rol"].in_contact == 2
    assert np.sort(q)[-2:] == pytest.approx([1500 / (2 * np.cos(np.pi / 10))] * 2, rel=1e-8)
    assert op.bearings["rol"].load == pytest.approx(1500.0, rel=1e-10)


def test_ball_bearing_with_a_large_clearance_carries_the_load_on_one_ball() -> None:
    """Z = 8 balls, clearance 100 um, 1.5 kN onto ball 6 (270 deg): only that ball touches
    (its neighbours at +-45 deg stay open), ``d = c + (F / K)^(2/3)``. The motion across the
    load is then unresisted: the operating point is refused for the dynamics, naming the
    bearing closed along one direction only."""
    m = _rotor(kind="ball", Z=8, c=100e-6)
    with pytest.raises(ModelError, match=r"body 'r' moves laterally .*'rol' has 1 of 8"):
        m.operating_point(1.0)
    m.add_bearing("side", "r", 0, stiffness=[1e5, 0.0], components=["ux", "uy"])
    op = m.operating_point(1.0)
    d = op.bearings["rol"].deflection[:2]
    want = 100e-6 + (1500.0 / K_N["ball"]) ** (2 / 3)
    assert d[1] == pytest.approx(-want, rel=1e-9) and abs(d[0]) < 1e-12
    assert op.bearings["rol"].in_contact == 1


def _cases() -> list[tuple[str, int, float, float, float]]:
    """(kind, Z, clearance / static deflection, load angle, element angle): clearance up
    to 10x the static deflection, the load on an element and between two."""
    out = []
    for kind in ("ball", "roller"):
        for Z in (7, 12, 17):
            for ratio in (0.0, 0.3, 3.0, 10.0):
                for where in (0.0, 0.5, 0.23):  # on element 0, halfway, in between
                    out.append((kind, Z, ratio, 2 * np.pi * where / Z + 0.4, 0.4))
    return out


@pytest.mark.parametrize("kind, Z, ratio, load_angle, angle", _cases())
def test_rigid_rotor_on_any_bearing_finds_the_equilibrium_of_the_element_sums(
    kind: str, Z: int, ratio: float, load_angle: float, angle: float
) -> None:
    F = 2000.0
    n, K = N_EXP[kind], K_N[kind]
    static = (F / (K * Z / 4)) ** (1 / n)  # about the deflection without clearance
    c = ratio * static
    fvec = F * np.array([np.cos(load_angle), np.sin(load_angle)])
    m = _rotor(kind=kind, Z=Z, c=c, load=(fvec[0], fvec[1], 0.0), angle=angle)
    m.add_bearing("side", "r", 0, stiffness=1e3, components=["ux", "uy"])  # a soft hold
    op = m.operating_point(1.0)
    d = op.bearings["rol"].deflection[:2]
    force, _ = _sums(kind, Z, c, angle)
    ref = root(lambda x: force(x) + 1e3 * x - fvec, d, tol=1e-14).x
    assert np.linalg.norm(force(d) + 1e3 * d - fvec) <= 1e-9 * F
    assert np.allclose(d, ref, rtol=0, atol=1e-9 * np.linalg.norm(ref))


@pytest.mark.parametrize("c", [10e-6, 40e-6, 100e-6, 300e-6])
def test_radial_law_at_any_clearance_is_the_closed_form(c: float) -> None:
    """``|F| = K <|d| - c>^n`` along ``d``: ``|d| = c + (F / K)^(1/n)`` (40 and 300 um were
    refused, 10 and 100 um found)."""
    op = _rotor(law="radial", kind="roller", Z=0, c=c).operating_point(1.0)
    d = op.bearings["rol"].deflection
    assert np.linalg.norm(d) == pytest.approx(c + (1500.0 / 1.5e9) ** 0.9, rel=1e-10)


def test_rotor_on_two_bearings_with_clearance_follows_the_lever_rule() -> None:
    """A rigid rotor on a roller bearing (z = 0, clearance 25 um) and a ball bearing (z =
    0.5 m, clearance 60 um), a 3 kN load at z = 0.2 m between them: statically determinate,
    so each bearing carries its lever-rule share (1.8 and 1.2 kN), and each deflects as its
    own element sums say."""
    m = rl.Model()
    m.add_rigid_body("d", (0, 0, 0.2), 20.0, (0.15, 0.15, 0.3))
    m.add_rigid_body("ja", (0, 0, 0.0), 1e-9, (1e-12, 1e-12, 2e-12))
    m.add_rigid_body("jb", (0, 0, 0.5), 1e-9, (1e-12, 1e-12, 2e-12))
    for j in ("ja", "jb"):
        m.add_rigid_link(f"l_{j}", "d", 0, j, 0)
    m.add_bearing("axial", "d", 0, stiffness=[1e8, 1e4], components=["uz", "phiz"])
    m.add_rolling_bearing("A", "ja", 0, kind="roller", stiffness=K_N["roller"], elements=12,
                          clearance=25e-6, angle=0.1)  # fmt: skip
    m.add_rolling_bearing("B", "jb", 0, kind="ball", stiffness=K_N["ball"], elements=9,
                          clearance=60e-6)  # fmt: skip
    m.add_force("load", "d", 0, force=(0.0, -3000.0, 0.0))
    op = m.operating_point(1.0)
    for name, kind, Z, c, angle, share in (("A", "roller", 12, 25e-6, 0.1, 1800.0),
                                           ("B", "ball", 9, 60e-6, 0.0, 1200.0)):  # fmt: skip
        b = op.bearings[name]
        assert b.load == pytest.approx(share, rel=1e-8)
        force, _ = _sums(kind, Z, c, angle)
        target = np.array([0.0, -share])
        ref = root(lambda x, f=force, t=target: f(x) - t, b.deflection[:2], tol=1e-15).x
        assert np.allclose(b.deflection[:2], ref, rtol=0, atol=1e-9 * np.linalg.norm(ref))


def test_a_load_no_joint_can_carry_is_refused_naming_the_bearing_and_the_load() -> None:
    """A table bearing whose force saturates at 1 kN (flat beyond 50 um) under 1.5 kN: no
    equilibrium exists; the refusal names the bearing, the load it would carry and what its
    law gives, in N."""
    d = [0.0, 20e-6, 50e-6, 100e-6]
    f = [0.0, 600.0, 1000.0, 1000.0]
    m = _rotor(law="table", Z=0, c=0.0, deflection=d, force=f, K=0.0)
    with pytest.raises(ModelError, match=r"does not exist.*bearing 'rol' would carry 1500 N, "
                                         r"but its law gives 1000 N"):  # fmt: skip
        m.operating_point(1.0)


def test_a_free_body_the_static_load_pushes_is_refused_naming_it() -> None:
    """Nothing holds the rotor laterally and gravity pulls it: no static equilibrium."""
    m = rl.Model()
    m.add_rigid_body("r", (0, 0, 0), 10.0, (0.1, 0.1, 0.2))
    m.add_bearing("axial", "r", 0, stiffness=[1e8, 1e6, 1e6, 1e4],
                  components=["uz", "phix", "phiy", "phiz"])  # fmt: skip
    m.add_torque("t", "r", 0, 5.0)
    m.set_gravity((0.0, -9.81, 0.0))
    with pytest.raises(ModelError, match=r"body 'r' moves laterally.*98.1 N"):
        m.operating_point(1.0)


def test_a_torque_nothing_balances_is_said_in_newton_metres_with_the_torques() -> None:
    """A gear pair (20:50) driven by 100 N m with -200 N m on the output and no torsional
    support: the drive train's free rotation carries ``100 + (-200)(-20/50) = 180`` N m at
    the pinion, which the constant-speed assumption takes; said with the torques."""
    z1, z2, mod = 20, 50, 0.004
    m = rl.Model()
    m.add_rigid_body("p", (0, 0, 0), 1.0, (1e-3, 1e-3, 2e-3))
    m.add_rigid_body("g", (mod * (z1 + z2) / 2, 0, 0), 3.0, (0.01, 0.01, 0.02))
    for b in ("p", "g"):
        m.add_bearing(f"{b}b", b, 0, stiffness=1e9, components=["ux", "uy", "uz", "phix", "phiy"])
    m.add_gear_mesh("m", "p", 0, "g", 0, z1, z2, mod, stiffness=4e8, load_law="iso6336",
                    face_width=0.02)  # fmt: skip
    m.add_torque("in", "p", 0, 100.0)
    m.add_torque("out", "g", 0, -200.0)
    op = m.operating_point(1.0)
    (held,) = op.held_loads()
    assert held["body"] == "p" and held["unit"] == "N m"
    assert held["load"] == pytest.approx(100.0 + (-200.0) * (-z1 / z2), rel=1e-9)
    (note,) = op.notes()
    assert "180 N m at body 'p'" in note and "in 100 N m, out -200 N m" in note


def test_a_bearing_far_too_soft_for_its_load_is_refused_with_the_load_of_the_static_balance():
    """The preloaded example's roller bearing 'pB' with stiffness 1 N/m^(10/9) instead of
    1.5e9 (a case bench/fuzz.py found refused as "Newton did not converge"). The pinion shaft
    rests on 'pA' and 'pB' with its disk half-way, so the moment balance about 'pA' fixes the
    load of 'pB' whatever the stiffnesses: half of the mesh force F_n = T / r_b1 (along the
    line of action at the operating pressure angle, cos a' = (r_b1 + r_b2) / 147 mm) plus
    the shaft's weight (disk and shaft, steel 7850 kg/m^3). The example finds that load; the
    soft bearing would need (766 N / K)^(9/10) = 391 m of deflection, far beyond 1 % of the
    model (1.47 mm), where its law gives K (1.47 mm)^(10/9): no equilibrium exists, and the
    refusal names 'pB' and that load in N."""
    import math
    import re
    import tomllib

    import tomli_w

    from rheolin.data import example_text
    from rheolin.io import parse_model

    g, rho, alpha = 9.81, 7850.0, math.radians(20.0)
    weight = rho * math.pi * (0.042**2 * 0.020 + 0.015**2 * 0.080) * g
    r_b1, r_b2 = 0.042 * math.cos(alpha), 0.104 * math.cos(alpha)
    Fn, a_op = 60.0 / r_b1, math.acos((r_b1 + r_b2) / 0.147)
    load = 0.5 * math.sqrt(Fn**2 + weight**2 + 2 * Fn * weight * math.cos(a_op))

    doc = tomllib.loads(example_text("preloaded"))
    speed = 1000 * math.pi / 30
    op = parse_model(tomli_w.dumps(doc)).model.operating_point(speed)
    assert op.bearings["pB"].load == pytest.approx(load, rel=1e-9)
    doc["shafts"][0]["rolling_bearings"][1]["stiffness"] = 1
    with pytest.raises(ModelError) as info:
        parse_model(tomli_w.dumps(doc)).model.operating_point(speed)
    text = str(info.value)
    found = re.search(r"does not exist.*bearing 'pB' would carry ([\d.e+]+) N, but its law "
                      r"gives ([\d.e+-]+) N at 1\.47 mm", text)  # fmt: skip
    assert found, text
    assert float(found[1]) == pytest.approx(load, rel=1e-3)  # printed to 4 digits
    assert float(found[2]) == pytest.approx(1.0 * 1.47e-3 ** (10 / 9), rel=1e-3)
    assert (load / 1.0) ** 0.9 > 100.0  # the deflection the balance needs [m]
