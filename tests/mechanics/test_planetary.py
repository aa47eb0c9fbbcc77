"""Planetary sets against independent references: Lin & Parker's carrier-frame model
(planetary_reference.py, from the papers' equations), their published modal structure, the
Willis equation's textbook ratios, Parker's mesh-phasing rule, rotation matrices evaluated in
time, and the monodromy matrix of the reference."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from planetary_cases import AXIS, build, state_function
from planetary_reference import MEMBERS, LinParker, monodromy
from scipy.linalg import eig, eigh, expm
from scipy.spatial.transform import Rotation

import rheolin as rl
from rheolin.errors import ModelError
from rheolin.mechanics.carrier_frame import (
    carried_speed_term,
    planet_inertia_term,
    planet_mesh_term,
)
from rheolin.mechanics.planetary import PlanetaryGeometry, equal_spacing, mesh_phases, phased
from rheolin.mechanics.planetary_modes import SetDofs, planetary_mode_kinds
from rheolin.mechanics.rotation import rotation_series
from rheolin.mechanics.willis import carried_pair, fixed_pair, solve_speeds
from rheolin.stability.modes import averaged_modes

DEG = np.pi / 180


# ------------------------------------------------------------------ the reference itself
def _kinds(ref: LinParker, vectors: np.ndarray) -> list[str]:
    """Lin & Parker's mode types from (possibly complex) shapes: central members only rotate
    and the planets move alike (rotational), central members only translate (translational),
    central members at rest (planet)."""
    out = []
    for v in vectors.T:
        v = v / np.max(np.abs(v))
        central = np.concatenate([v[ref.index(j)] for j in MEMBERS]).reshape(3, 3)
        planets = np.array([v[ref.index("p", n)] for n in range(ref.n_planets)])
        if np.abs(central).max() < 1e-8:
            out.append("planet")
        elif np.abs(central[:, :2]).max() < 1e-8 and np.allclose(planets, planets[0], atol=1e-8):
            out.append("rotational")
        elif np.abs(central[:, 2]).max() < 1e-8:
            out.append("translational")
        else:
            out.append("?")
    return out


@pytest.mark.parametrize("planets", [4, 5])
def test_reference_has_lin_parkers_modal_structure(planets):
    """Lin & Parker 1999: 6 rotational modes (simple), 6 translational modes (pairs) and 3
    planet modes of multiplicity N - 3, for equally spaced identical planets."""
    case = build(planets=planets, teeth=(20, 20, 60), damping=0.0)
    ref = case.reference
    M, _, K, _ = ref.matrices(0.0, 0.0)
    lam, V = eigh(K, M)
    f = np.sqrt(lam)
    groups = np.split(np.arange(f.size), np.flatnonzero(np.diff(f) > 1e-6 * f.max()) + 1)
    kinds: dict[str, list[int]] = {"rotational": [], "translational": [], "planet": []}
    for g in groups:
        sub = V[:, g]
        if g.size > 1:  # a degenerate group: classify any vector of it the same way
            sub = sub @ np.linalg.qr(np.random.default_rng(0).normal(size=(g.size, g.size)))[0]
        k = set(_kinds(ref, sub))
        assert len(k) == 1, (f[g], k)
        kinds[k.pop()].append(g.size)
    assert kinds["rotational"] == [1] * 6
    assert kinds["translational"] == [2] * 6
    assert kinds["planet"] == [planets - 3] * 3


# ------------------------------------------------------------------ geometry
def test_mesh_vectors_follow_lin_parkers_deflections():
    """Every planet's in-plane mesh vectors are Lin & Parker's delta_sn, delta_rn (both flanks:
    the other flank is alpha -> -alpha with the deflection's sign reversed); the torsional
    entries, the lines' moment arms, are the base radii: each line is tangent to both circles."""
    g = PlanetaryGeometry(
        17, 26, 70, [0.0, 2 * np.pi * 23 / 87, 2 * np.pi * 57 / 87], 0.004, 22 * DEG
    )
    rbs, rbp, rbr = (g.base_radius(z) for z in (17, 26, 70))
    for sigma in (1, -1):
        c = g.contacts(AXIS, [1, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], sigma)
        for n, psi in enumerate(g.planet_angles):
            a_s, a_r = sigma * g.sun_pressure_angle, sigma * g.ring_pressure_angle
            ps, pr = psi - a_s, psi + a_r
            rot = np.array([[np.cos(psi), -np.sin(psi)], [np.sin(psi), np.cos(psi)]])
            # sun: (x_s, y_s, u_s = r_bs theta_s) and planet (zeta, eta, u_n = r_bp theta_n)
            lp_s = [-np.sin(ps), np.cos(ps), -np.sin(a_s), -np.cos(a_s)]
            w = c[n].sun
            planet = rot.T @ w[6:8]  # planet translation along (radial, tangential)
            got = [w[0], w[1], *planet, w[5] / rbs, w[11] / rbp]
            assert np.allclose(got, sigma * np.array([*lp_s, 1.0, 1.0]), atol=1e-12)
            lp_r = [-np.sin(pr), np.cos(pr), np.sin(a_r), -np.cos(a_r)]
            w = c[n].ring
            planet = rot.T @ w[6:8]
            got = [w[0], w[1], *planet, w[5] / rbr, w[11] / rbp]
            assert np.allclose(got, sigma * np.array([*lp_r, 1.0, -1.0]), atol=1e-12)
        assert c[0].position @ [1, 0, 0] == pytest.approx(g.carrier_radius)


def test_helical_planet_thrusts_cancel_into_a_tilting_moment():
    """With helical teeth the sun's and the ring's axial thrusts on a planet cancel (both
    tangential forces point the same way) and leave a moment about the planet's radial axis."""
    g = PlanetaryGeometry(21, 39, 99, equal_spacing(3), 0.010, 20 * DEG, 7.5 * DEG)
    c = g.contacts(AXIS, [1, 0, 0], [0, 0, 0], [0, 0, 0.1], [0, 0, -0.05])
    for pc in c:
        f_s, f_r = -pc.sun[6:9], -pc.ring[6:9]  # force on the planet per unit compression
        assert f_s @ pc.tangential == pytest.approx(
            f_r @ pc.tangential * (np.cos(g.sun_pressure_angle) / np.cos(g.ring_pressure_angle)),
            rel=1e-12,
        )
        assert f_s @ AXIS == pytest.approx(
            -f_r @ AXIS * (f_s @ pc.tangential) / (f_r @ pc.tangential), rel=1e-12
        )
        assert abs(f_s @ AXIS) == pytest.approx(np.sin(g.base_helix_angle), rel=1e-12)
        moment = -pc.sun[9:12] - pc.ring[9:12] * (f_s @ pc.tangential) / (f_r @ pc.tangential)
        assert abs(moment @ pc.radial) > 0.1 * g.base_radius(39) * abs(f_s @ AXIS)
        assert abs(moment @ AXIS) < 1e-12 * g.base_radius(39)
    # the sun and ring nodes off the planets' plane carry the thrust's lever
    assert abs(c[0].sun[3:6] @ c[0].tangential) > 0


@pytest.mark.parametrize(
    ("teeth", "angles", "field"),
    [
        ((21, 39, 98), equal_spacing(3), "ring_teeth"),  # smaller than sun + 2 planets
        ((21, 39, 100), equal_spacing(3), "ring_teeth"),  # (21 + 100) / 3 not an integer
        ((20, 20, 70), equal_spacing(3), "ring_teeth"),  # centre distances 10 % apart
        ((20, 20, 60), [0.0, 100 * DEG, 200 * DEG], "planet_angles[1]"),  # 80 * 100/360
        ((20, 20, 60), [0.0, 45 * DEG, 180 * DEG], "planet_angles"),  # 45 deg: they collide
        ((20, 20, 60), equal_spacing(6), "planet_angles"),  # six do not fit
    ],
)
def test_geometry_refuses_sets_that_cannot_be_built(teeth, angles, field):
    with pytest.raises(ModelError, match=rf"`{field.replace('[', '.').replace(']', '.')}`"):
        PlanetaryGeometry(*teeth, angles, 0.003, 20 * DEG)


def test_unequal_spacing_that_assembles_is_accepted():
    """(z_s + z_r) psi / 360 deg an integer: 80 teeth, 4.5 deg steps."""
    g = PlanetaryGeometry(20, 20, 60, [0.0, 121.5 * DEG, 238.5 * DEG], 0.003, 20 * DEG)
    assert not g.equally_spaced and g.planets == 3
    s, r = mesh_phases(g, 1)
    assert np.allclose(np.exp(1j * s), np.exp(1j * r))  # gamma_rn = gamma_sn (assembly)


# ------------------------------------------------------------------ kinematics
@pytest.mark.parametrize(
    ("held", "drive", "expected"),
    [  # textbook ratios of a simple set, z_s = 21, z_r = 99 (Willis)
        ("ring", "sun", {"carrier": (21, 120)}),
        ("ring", "carrier", {"sun": (120, 21)}),
        ("carrier", "sun", {"ring": (-21, 99)}),
        ("sun", "ring", {"carrier": (99, 120)}),
    ],
)
def test_willis_ratios(held, drive, expected):
    cons = [
        carried_pair("sun", "p", "carrier", 21, 39, False, "sun mesh"),
        carried_pair("ring", "p", "carrier", 99, 39, True, "ring mesh"),
    ]
    r = solve_speeds(drive, cons, fixed_ratios={held: 0})
    for body, (a, b) in expected.items():
        assert r[body] == Fraction(a, b)
    assert (r["p"] - r["carrier"]) * 39 == -(r["sun"] - r["carrier"]) * 21
    assert (r["ring"] - r["carrier"]) * 99 == -(r["sun"] - r["carrier"]) * 21


def test_willis_compound_train_and_refusals():
    """Two planetary stages in series (the second's carrier driven by the first's sun through
    a shaft, NREL 5 MW-like) and a parallel stage: the product of the textbook ratios."""
    cons = [
        carried_pair("sun1", "p1", "c1", 21, 39, False, "stage 1"),
        carried_pair("ring1", "p1", "c1", 99, 39, True, "stage 1"),
        carried_pair("sun2", "p2", "sun1", 20, 30, False, "stage 2"),  # carrier 2 = sun 1
        carried_pair("ring2", "p2", "sun1", 80, 30, True, "stage 2"),
        fixed_pair("sun2", "pinion", 90, 22, False, "parallel stage"),
        fixed_pair("shaft", "idle", 30, 40, False, "a train nothing drives"),
    ]
    r = solve_speeds("c1", cons, fixed_ratios={"ring1": 0, "ring2": 0})
    assert r["sun1"] * 21 == 120 and r["sun2"] == r["sun1"] * 5
    assert r["pinion"] == -r["sun2"] * 90 / 22
    assert r["shaft"] == 0 and r["idle"] == 0
    with pytest.raises(
        ModelError, match=r"does not determine the speeds of \[.p2., .pinion., .ring2., .sun2.\]"
    ):
        solve_speeds("c1", cons, fixed_ratios={"ring1": 0})
    with pytest.raises(ModelError, match="stage 2 gives speeds that contradict"):
        solve_speeds("c1", cons, fixed_ratios={"ring1": 0, "ring2": 0, "sun2": 1})


# ------------------------------------------------------------------ mesh phasing
def _parker_rule(harmonic: int, sun_teeth: int, planets: int) -> str:
    """Parker, J. Sound Vib. 236(4) 2000: for equally spaced planets the l-th mesh harmonic
    excites only rotational modes when l z_s / N is an integer, only translational modes when
    (l z_s +- 1) / N is, and neither otherwise."""
    if harmonic * sun_teeth % planets == 0:
        return "rotational"
    if (harmonic * sun_teeth + 1) % planets == 0 or (harmonic * sun_teeth - 1) % planets == 0:
        return "translational"
    return "none"


@pytest.mark.parametrize(
    ("teeth", "planets"),
    [((21, 39, 99), 3), ((23, 25, 73), 4), ((27, 23, 73), 5), ((20, 20, 60), 4)],
)
def test_mesh_phasing_cancels_as_parker_predicts(teeth, planets):
    """The net force and torque on the sun of every planet's phased transmission-error load,
    harmonic by harmonic, vanish or not exactly as the rule says (the force turns with the
    carrier, so the l-th harmonic's force is read at l m +- s_c in the fixed frame)."""
    zs, zp, zr = teeth
    g = PlanetaryGeometry(zs, zp, zr, equal_spacing(planets), 0.003, 20 * DEG)
    contacts = g.contacts(AXIS, [1, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0])
    gamma, _ = mesh_phases(g, 1)
    m, s_c = 1000, 1  # mesh harmonic, carrier spin
    for harmonic in range(1, 2 * planets + 1):
        te = {harmonic: 1e-6}
        force = {}
        for c, gam in zip(contacts, gamma, strict=True):
            t = planet_mesh_term(
                range(6), range(6, 12), c.sun, AXIS, s_c, m, {0: 1e8}, 0.0, phased(te, gam)
            )
            for k, v in t.f[0].items():
                force[k] = force.get(k, 0) + v[:6]
        scale = 1e8 * 1e-6
        torque = abs(force.get(harmonic * m, np.zeros(6))[5]) / g.base_radius(zs) / scale
        lateral = (
            max(np.abs(force.get(harmonic * m + d, np.zeros(6))[:2]).max() for d in (-s_c, s_c))
            / scale
        )
        expected = _parker_rule(harmonic, zs, planets)
        assert (torque > 1e-9) == (expected == "rotational"), (harmonic, torque)
        assert (lateral > 1e-9) == (expected == "translational"), (harmonic, lateral)
        if expected == "rotational":
            assert torque == pytest.approx(planets, rel=1e-12)


# ------------------------------------------------------------------ carrier-frame terms
def test_carried_term_is_the_rotated_element_in_time():
    """K(t), D(t) from the Fourier coefficients equal Q(t)^T X Q(t) + Q^T C Q'(t) and
    Q^T C Q with the rotation matrix Q(t) = diag(R(t)^T, R(t)^T, I6) built by SciPy."""
    rng = np.random.default_rng(3)
    A = rng.normal(size=(12, 12))
    X, C = A @ A.T, np.diag(rng.uniform(1, 2, 12))
    axis = np.array([0.3, -0.5, 0.8])
    axis /= np.linalg.norm(axis)
    s, w1 = 3, 1.7
    t = carried_speed_term(range(6), range(6, 12), axis, s, {0: X}, C).at(w1)
    for time in (0.0, 0.37, 1.91):

        def Q(tt):
            R = Rotation.from_rotvec(axis * s * w1 * tt).as_matrix()
            out = np.eye(12)
            out[:3, :3] = out[3:6, 3:6] = R.T
            return out

        h = 1e-6
        dQ = (Q(time + h) - Q(time - h)) / (2 * h)
        K = sum(np.real(v * np.exp(1j * k * w1 * time)) for k, v in t.K.items())
        D = sum(np.real(v * np.exp(1j * k * w1 * time)) for k, v in t.D.items())
        assert np.allclose(K, Q(time).T @ X @ Q(time) + Q(time).T @ C @ dQ, atol=1e-7)
        assert np.allclose(D, Q(time).T @ C @ Q(time), atol=1e-12)


def test_planet_inertia_in_the_carrier_frame():
    """Lin & Parker's Coriolis 2 m W_c [e]x and centripetal -m W_c^2 on the translations;
    on the tilts the rotating-frame Euler equations of an axisymmetric rotor:
    J_d (psi'' + 2 W_c [e]x psi' + W_c^2 [e]x^2 psi) - W_p J_p [e]x (psi' + W_c [e]x psi)."""
    m, Jd, Jp, s_p, s_c, w1 = 0.7, 0.02, 0.03, -5, 2, 1.3
    t = planet_inertia_term(range(6), m, [Jd, Jd, Jp], AXIS, s_p, s_c, [0.2, 0.1, 0.0]).at(w1)
    Wc, Wp = s_c * w1, s_p * w1
    E = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    J = np.diag([Jd, Jd, Jp])
    D = np.zeros((6, 6))
    D[:3, :3] = 2 * m * Wc * E
    D[3:, 3:] = 2 * Wc * J @ E - Wp * Jp * E
    K = np.zeros((6, 6))
    K[:3, :3] = m * Wc**2 * E @ E
    K[3:, 3:] = Jd * Wc**2 * E @ E - Wp * Wc * Jp * E @ E
    assert sorted(t.M) == sorted(t.D) == sorted(t.K) == [0]
    assert np.allclose(t.M[0], np.diag([m, m, m, Jd, Jd, Jp]))
    assert np.allclose(t.D[0], D, atol=1e-14) and np.allclose(t.K[0], K, atol=1e-14)
    assert np.allclose(t.f[0], [m * Wc**2 * 0.2, m * Wc**2 * 0.1, 0, 0, 0, 0])


# ------------------------------------------------------------------ the whole set
def _mesh_periods(case) -> int:
    """Mesh periods per carrier revolution (the reference's coefficients have the mesh's)."""
    ratio = case.mesh_harmonic / case.spins["carrier"]
    assert ratio == int(ratio)
    return int(ratio)


@pytest.mark.parametrize(
    ("members", "held", "eps"),
    [("inertial", "ring", 0.0), ("inertial", "ring", 0.3), ("carrier", "sun", 0.3)],
    ids=[
        "inertial members, constant mesh",
        "inertial members, ring held, parametric",
        "members in the carrier frame, sun held, parametric",
    ],
)
def test_set_monodromy_equals_lin_parkers(members, held, eps):
    """Over one carrier revolution, rheolin's planar DOFs (planets in the carrier frame, the
    sun, ring and carrier inertial or in the carrier frame too) and the reference (all in the
    carrier frame) are related by a periodic change of coordinates that is the identity at
    t = 0 and T: their monodromy matrices have the same eigenvalues. This checks the geometry,
    the frame terms, the gyroscopic and centripetal terms, damping on both sides and the mesh
    phasing at once."""
    case = build(held=held, eps=eps, members=members)
    T = 2 * np.pi / case.carrier_speed
    n = 2 * case.planar.size
    periods = _mesh_periods(case)
    if eps == 0:
        ref = expm(case.reference.state_matrix(0.0, case.carrier_speed) * T)
    else:
        ref = monodromy(case.reference.state_function(case.carrier_speed), T, n, periods)
    own = periods if members == "carrier" else 1  # inertial members turn at the carrier's
    got = monodromy(state_function(case.system, case.planar), T, n, own)
    a, b = np.linalg.eigvals(ref), np.linalg.eigvals(got)
    scale = np.abs(a).max()
    assert max(np.min(np.abs(b - x)) for x in a) < 1e-9 * scale
    assert max(np.min(np.abs(a - x)) for x in b) < 1e-9 * scale


@pytest.mark.parametrize("members", ["inertial", "carrier"])
def test_averaged_system_modes(members):
    """With the sun, ring and carrier in the carrier frame too, the set is time-invariant but
    for the mesh stiffness: the time-averaged system (modes, Campbell, the static equilibrium)
    has all of Lin & Parker's modes, gyroscopic terms included. With them inertial it keeps
    the rotational and planet modes only (they leave the central translations at rest, to
    which the planets couple through +-W_c)."""
    case = build(planets=5, teeth=(20, 20, 60), members=members)
    ref = case.reference
    lam, V = eig(ref.state_matrix(0.0, case.carrier_speed))
    keep = lam.imag > 0
    lam, V = lam[keep], V[: ref.n, keep]
    kinds = np.array(_kinds(ref, V))
    assert np.count_nonzero(kinds == "rotational") == 6
    assert np.count_nonzero(kinds == "planet") == 3 * (5 - 3)
    got = averaged_modes(case.system).eigenvalues
    assert np.count_nonzero(kinds == "translational") == 2 * 6
    exact = ["rotational", "planet"] + (["translational"] if members == "carrier" else [])
    for x in lam[np.isin(kinds, exact)]:
        assert np.min(np.abs(got - x)) < 1e-9 * abs(x), x
    if members == "inertial":
        assert min(np.min(np.abs(got - x)) for x in lam[kinds == "translational"]) > 1e-3


@pytest.mark.parametrize(("speed", "stable"), [(0.6, False), (0.625, True), (0.875, False)])
def test_parametric_instability_against_the_monodromy_matrix(speed, stable):
    """Mesh stiffness ripple 50 %, light damping: a narrow unstable band below 0.61 rad/s of
    the carrier, stable at 0.625, a strong resonance at 0.875. rheolin's Floquet verdict
    (lattice) and largest real part against the reference's monodromy matrix."""
    case = build(eps=0.5, damping=0.3, carrier_speed=speed, out_damping=20.0, members="carrier")
    T = 2 * np.pi / speed
    periods = _mesh_periods(case)
    phi = monodromy(case.reference.state_function(speed), T, 2 * case.planar.size, periods)
    expected = np.log(np.abs(np.linalg.eigvals(phi))).max() / T
    res = rl.floquet(case.system)
    assert res.decided and bool(res.stable) == stable and bool(expected < 0) == stable
    assert res.max_real == pytest.approx(expected, abs=1e-4)


def test_load_sharing_with_a_pin_error():
    """A tangential pin error unloads its planet; the sun floats to share the load. rheolin's
    periodic steady state (the sun's translation turns with the carrier: harmonics +-W_c) gives
    each mesh's mean force as the reference's static carrier-frame solution does."""
    errors = (np.array([0.0, 2e-3]), np.zeros(2), np.zeros(2), np.zeros(2))  # scaled model
    case = build(eps=0.0, pin_errors=errors, sun_torque=0.5)
    s_c = case.spins["carrier"]
    sol = rl.solve(case.system, [-2 * s_c, -s_c, 0, s_c, 2 * s_c], method="direct", stability=False)
    assert sol.success
    ref = case.reference
    _, _, K, f = ref.matrices(0.0, case.carrier_speed)
    u = np.linalg.solve(K, f)
    gs, gr, _ = ref.gradients()
    ks, kr = ref.ks(0.0), ref.kr(0.0)
    for n in range(4):
        for kind, grads, k in (("sun", gs, ks), ("ring", gr, kr)):
            mesh = case.meshes[f"set.{kind}{n}"]
            delta = sum(
                g @ sol.harmonic(-h)[mesh.dofs]
                for h, g in mesh.vector.items()
                if -h in sol.harmonics
            )
            assert k[n] * np.real(delta) == pytest.approx(k[n] * grads[n] @ u, rel=1e-9)
    loads = [ks[n] * gs[n] @ u for n in range(4)]
    assert (max(loads) - min(loads)) / np.mean(loads) > 0.03  # the error matters


def test_transmission_error_response_against_time_integration():
    """Phased mesh stiffness ripple and transmission error: the harmonic-balance steady state
    against the BDF time integration of the same system (``method="transient"``), and the
    same set solved with inertial sun, ring and carrier, turned back by R(t): the change of
    frame is exact for the forced response too."""
    kw = dict(eps=0.2, te=1e-3, damping=10.0, out_damping=20.0)  # scaled model
    case = build(members="carrier", **kw)
    H = rl.HarmonicSet.closure(case.system, order=4)
    hb = rl.solve(case.system, H, method="gmres", stability=True)
    assert hb.success and hb.stable
    td = rl.solve(case.system, H, method="transient")
    assert td.success
    peak = np.abs(hb.q).max()
    for h in (case.mesh_harmonic, 2 * case.mesh_harmonic):
        assert np.abs(hb.harmonic(h) - td.harmonic(h)).max() < 1e-4 * peak
    inertial = build(members="inertial", **kw)
    Hi = rl.HarmonicSet.closure(inertial.system, order=4)
    q = rl.solve(inertial.system, Hi, method="gmres", stability=False)
    assert q.success
    R = rotation_series(AXIS, case.spins["carrier"])  # the members' q = R6(t) z
    for h in (case.mesh_harmonic, case.mesh_harmonic + 1, case.mesh_harmonic - 1):
        expected = np.zeros(hb.q.shape[1], dtype=complex)
        for k, P in R.items():
            if h - k in hb.harmonics:
                expected += np.kron(np.eye(2 * 3 + 2 * 4), P) @ hb.harmonic(h - k)
        expected[18:] = hb.harmonic(h)[18:] if h in hb.harmonics else 0  # planets: unchanged
        assert np.abs(q.harmonic(h) - expected).max() < 1e-8 * peak


def test_mode_labels_are_lin_parkers_types():
    """Labels of rheolin's averaged modes (set in the carrier frame, five planets) against the
    types of the reference's modes at the same eigenvalues, and their counts."""
    case = build(planets=5, teeth=(20, 20, 60), members="carrier")
    ref = case.reference
    lam, V = eig(ref.state_matrix(0.0, case.carrier_speed))
    keep = lam.imag > 0
    lam, kinds = lam[keep], np.array(_kinds(ref, V[: ref.n, keep]))
    modes = averaged_modes(case.system)
    node = np.arange(3)
    dofs = SetDofs(
        np.concatenate([6 * node, 6 * node + 1]), 6 * node + 5, np.arange(18, case.system.n)
    )
    labels = planetary_mode_kinds(modes.shapes, case.system.M[0].diagonal(), dofs)
    planar = [i for i, x in enumerate(modes.eigenvalues) if np.min(np.abs(lam - x)) < 1e-9]
    assert len(planar) == lam.size
    for i in planar:
        assert labels[i] == kinds[np.argmin(np.abs(lam - modes.eigenvalues[i]))]
    assert sorted(labels[planar]).count("planet") == 6
    assert sorted(labels[planar]).count("translational") == 12
