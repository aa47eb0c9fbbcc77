"""One planetary set built twice: with rheolin's terms (sun, ring and carrier inertial, planets
in the carrier frame, six DOFs per node) and as Lin & Parker's planar carrier-frame model
(planetary_reference.py), from the same parameters. Frequencies are scaled to a few times the
carrier speed so that time integration over a carrier revolution stays cheap."""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np
from planetary_reference import LinParker

from rheolin.mechanics._term import SpeedTerm
from rheolin.mechanics.assembly import assemble_coefficients
from rheolin.mechanics.frames import in_frame
from rheolin.mechanics.joints import joint_term
from rheolin.mechanics.planetary import PlanetaryGeometry, equal_spacing
from rheolin.mechanics.planetary_terms import (
    MeshFamily,
    PlanetData,
    SetMesh,
    SetNodes,
    planetary_speed_terms,
)
from rheolin.mechanics.rigid import RigidNode
from rheolin.mechanics.speeds import rational_gcd
from rheolin.mechanics.willis import carried_pair, solve_speeds
from rheolin.system.periodic import PeriodicSystem

#: Lin & Parker's example sizes (masses [kg], I / r^2 [kg]), stiffnesses scaled by SCALE.
MASS = {"s": 0.4, "r": 2.35, "c": 5.43, "p": 0.66}
I_R2 = {"s": 0.39, "r": 3.0, "c": 6.29, "p": 0.61}
SCALE = 5e-7
AXIS = np.array([0.0, 0.0, 1.0])
MEMBER = {"s": "sun", "r": "ring", "c": "carrier"}
#: Axial and tilting stiffness of every node (the planar reference leaves them out; with the
#: unit diametral inertias here they sit near 17 rad/s, clear of the harmonics used).
OUT = 300.0


@dataclass
class Case:
    system: PeriodicSystem
    reference: LinParker
    geometry: PlanetaryGeometry
    w1: float
    carrier_speed: float
    spins: dict[str, int]
    mesh_harmonic: int
    meshes: dict[str, SetMesh]
    planar: np.ndarray  # rheolin's (ux, uy, phiz) DOFs in the reference's member order
    radius: dict[str, float]


def build(
    held: str = "ring",
    teeth: tuple[int, int, int] = (12, 12, 36),
    planets: int = 4,
    eps: float = 0.0,
    damping: float = 1.0,
    te: float = 0.0,
    pin_errors: tuple[np.ndarray, ...] = (),
    sun_torque: float = 0.0,
    carrier_speed: float = 1.0,
    out_damping: float = 0.0,
    members: str = "inertial",
    scale: float = SCALE,
) -> Case:
    """The set with ``held`` member fixed (``"ring"``: sun input; ``"sun"``: ring input), mesh
    stiffness ripple ``eps``, static transmission error amplitude ``te`` [m] on every mesh,
    pin errors per planet (radial, tangential), a static torque on the sun [N m], the carrier
    speed [rad/s] and the damping of the axial and tilting motions (which the planar reference
    leaves out); ``members="carrier"`` writes the sun, ring and carrier in the carrier's axes
    too."""
    zs, zp, zr = teeth
    geo = PlanetaryGeometry(zs, zp, zr, equal_spacing(planets), 0.005, np.radians(20))
    names = [f"p{n}" for n in range(planets)]
    cons = []
    for p in names:
        cons += [
            carried_pair("sun", p, "carrier", zs, zp, False, "sun mesh"),
            carried_pair("ring", p, "carrier", zr, zp, True, "ring mesh"),
        ]
    drive = "sun" if held == "ring" else "ring"
    ratios = solve_speeds(drive, cons, fixed_ratios={held: 0})
    mesh = zs * abs(ratios["sun"] - ratios["carrier"])
    base = rational_gcd([*ratios.values(), mesh])
    spin = {k: int(v / base) for k, v in ratios.items()}
    spin["planet"] = spin["p0"]
    mh = int(Fraction(mesh) / base)
    w1 = carrier_speed / spin["carrier"]
    radius = {
        "s": geo.base_radius(zs),
        "r": geo.base_radius(zr),
        "c": geo.carrier_radius,
        "p": geo.base_radius(zp),
    }
    J = {j: I_R2[j] * radius[j] ** 2 for j in MASS}
    k = {j: 1e8 * scale for j in "src"}
    ku = {"s": 0.2e9 * scale, "r": 1e9 * scale, "c": 0.3e9 * scale}
    kp, ksp, krp = 1e8 * scale, 5e8 * scale, 5e8 * scale
    f = float(damping)  # damping scale
    c = {j: f * 0.03 * np.sqrt(k[j] * MASS[j]) for j in "src"}
    cu = {j: f * 0.01 * np.sqrt(ku[j] * I_R2[j]) for j in "src"}
    cp = f * 0.03 * np.sqrt(kp * MASS["p"])
    cs, cr = f * 0.02 * np.sqrt(ksp * MASS["p"]), f * 0.01 * np.sqrt(krp * MASS["p"])
    ks = {0: ksp, 1: eps * ksp / 2 * np.exp(0.3j), 2: eps * ksp / 5}
    kr = {0: krp, 1: eps * krp / 2 * np.exp(-0.7j)}
    e_s = {1: te / 2} if te else None
    e_r = {1: te / 2 * np.exp(1j)} if te else None

    terms: list[SpeedTerm] = []
    loads: dict[int, np.ndarray] = {}
    n_dof = 6 * (3 + planets)
    for i, j in enumerate("src"):
        dofs = 6 * i + np.arange(6)
        node = RigidNode(MASS[j], np.diag([1.0, 1.0, J[j]]))
        K = np.diag([k[j], k[j], OUT, OUT, OUT, ku[j] * radius[j] ** 2])
        C = np.diag([c[j], c[j], *[out_damping] * 3, cu[j] * radius[j] ** 2])
        own = [node.speed_term(i, AXIS, spin[MEMBER[j]])]
        own.append(SpeedTerm.constant(joint_term(dofs, None, K, C)))
        if members == "carrier":
            own = [in_frame(t, {2 * i, 2 * i + 1}, AXIS, spin["carrier"]) for t in own]
        terms += own
    if sun_torque:
        loads[0] = np.zeros(n_dof)
        loads[0][5] = sun_torque
    planet_dofs = [6 * (3 + n) + np.arange(6) for n in range(planets)]
    origin = np.zeros(3)
    nodes = SetNodes(
        (np.arange(6), origin),
        (6 + np.arange(6), origin),
        (12 + np.arange(6), origin),
        planet_dofs,
        AXIS,
        np.array([1.0, 0.0, 0.0]),
    )
    KB = np.diag([kp, kp, OUT, OUT, OUT, 0.0])
    DB = np.diag([cp, cp, *[out_damping] * 3, 0.0])
    planet = PlanetData(MASS["p"], np.array([1.0, 1.0, J["p"]]), KB, DB, pin_errors)
    pt, meshes = planetary_speed_terms(
        "set",
        geo,
        nodes,
        planet,
        MeshFamily(ks, cs, e_s),
        MeshFamily(kr, cr, e_r),
        spin,
        mh,
        member_spins=dict.fromkeys(MEMBER.values(), spin["carrier"] * (members == "inertial")),
    )
    terms += pt
    Ms, Ds, Ks, fs = assemble_coefficients([t.at(w1) for t in terms], n_dof)
    for h, v in loads.items():
        fs[h] = fs.get(h, 0) + v
    system = PeriodicSystem(w1, M=Ms, D=Ds, K=Ks, f=fs)

    # the reference, Lin & Parker's coordinates; the other flank is alpha -> -alpha with the
    # deflection's sign reversed (planetary_reference.py)
    sigma = int(np.sign(spin["sun"] - spin["carrier"]))
    psi = np.asarray(geo.planet_angles)
    Wm = mh * w1
    gs = sigma * zs * psi
    gr = -sigma * zr * psi

    def series(coefs, phase):
        def at(t):
            out = np.zeros(planets)
            for j, cj in coefs.items():
                out += (2 - (j == 0)) * np.real(cj * np.exp(1j * j * (Wm * t - phase)))
            return out

        return at

    ref = LinParker(
        psi,
        sigma * geo.sun_pressure_angle,
        sigma * geo.ring_pressure_angle,
        MASS,
        I_R2,
        k,
        ku,
        kp,
        series(ks, gs),
        series(kr, gr),
        c=c,
        cu=cu,
        cp=cp,
        cs=cs,
        cr=cr,
        es=None if not te else series({1: sigma * te / 2}, gs),
        er=None if not te else series({1: sigma * te / 2 * np.exp(1j)}, gr),
        carrier_radius=geo.carrier_radius,
        pin_errors=np.array(pin_errors) if pin_errors else None,
    )
    ref.static = np.zeros(ref.n)
    ref.static[ref.index("s").stop - 1] = sun_torque / radius["s"]
    planar = np.array([[6 * i, 6 * i + 1, 6 * i + 5] for i in range(3 + planets)]).ravel()
    return Case(system, ref, geo, w1, carrier_speed, spin, mh, meshes, planar, radius)


def dense_coefficients(system: PeriodicSystem, keep: np.ndarray) -> dict[str, list]:
    """``{name: [(k, X_k[keep, keep])]}`` of M, D, K."""
    out = {}
    for name in "MDK":
        rows = []
        for k, v in getattr(system, name).items():
            a = v.toarray() if hasattr(v, "toarray") else np.asarray(v)
            rows.append((k, a[np.ix_(keep, keep)]))
        out[name] = rows
    return out


def state_function(system: PeriodicSystem, keep: np.ndarray):
    """``t -> A(t)`` of rheolin's system on the DOFs ``keep`` (mass constant)."""
    X = dense_coefficients(system, keep)
    w1 = system.omega
    n = keep.size
    (M0,) = [v.real for k, v in X["M"] if k == 0]
    Mi = np.linalg.inv(M0)
    # [-Mi K_k, -Mi D_k] for k >= 0; the real signal is the k = 0 term plus 2 Re(k > 0)
    parts: dict[int, np.ndarray] = {}
    for col, name in ((0, "K"), (1, "D")):
        for k, v in X[name]:
            if k >= 0:
                blk = parts.setdefault(k, np.zeros((n, 2 * n), dtype=complex))
                blk[:, col * n : (col + 1) * n] -= (1.0 if k == 0 else 2.0) * (Mi @ v)
    ks = np.array(sorted(parts))
    stack = np.array([parts[k] for k in ks])
    top = np.hstack([np.zeros((n, n)), np.eye(n)])

    def A(t):
        bottom = np.tensordot(np.exp(1j * ks * w1 * t), stack, 1).real
        return np.vstack([top, bottom])

    return A


def model_case(
    held: str = "ring",
    teeth: tuple[int, int, int] = (12, 12, 36),
    planets: int = 4,
    eps: float = 0.0,
    carrier_speed: float = 1.0,
    out_damping: float = 0.0,
    frame: str = "carrier",
    te: float = 0.0,
    scale: float = SCALE,
    **extra,
):
    """:func:`build`'s set through ``Model.add_planetary`` (sun, ring and carrier rigid bodies
    on bearings to ground), and the input speed that gives ``carrier_speed``."""
    from rheolin.mechanics.model import Model

    zs, zp, zr = teeth
    drive = "sun" if held == "ring" else "ring"
    m = Model(input_body=drive)
    g = PlanetaryGeometry(zs, zp, zr, equal_spacing(planets), 0.005, np.radians(20))
    radius = {"s": g.base_radius(zs), "r": g.base_radius(zr), "c": g.carrier_radius,
              "p": g.base_radius(zp)}  # fmt: skip
    k = 1e8 * scale
    ku = {"s": 0.2e9 * scale, "r": 1e9 * scale, "c": 0.3e9 * scale}
    for j in "src":
        J = I_R2[j] * radius[j] ** 2
        m.add_rigid_body(MEMBER[j], (0, 0, 0), MASS[j], (1.0, 1.0, J),
                         speed_ratio=0 if MEMBER[j] == held else None)  # fmt: skip
        c = 0.03 * np.sqrt(k * MASS[j])
        cu = 0.01 * np.sqrt(ku[j] * I_R2[j])
        m.add_bearing(f"{j}_support", MEMBER[j], 0, [k, k, OUT, OUT, OUT, ku[j] * radius[j] ** 2],
                      [c, c, *[out_damping] * 3, cu * radius[j] ** 2], components=None)  # fmt: skip
    kp, ksp, krp = 1e8 * scale, 5e8 * scale, 5e8 * scale
    cp = 0.03 * np.sqrt(kp * MASS["p"])
    m.add_planetary(
        "set", "sun", 0, "ring", 0, "carrier", 0, zs, zp, zr, 0.005,
        planet={"mass": MASS["p"], "inertia": [1.0, 1.0, I_R2["p"] * radius["p"] ** 2]},
        planet_bearing={"stiffness": [kp, kp, OUT, OUT, OUT],
                        "damping": [cp, cp, *[out_damping] * 3]},
        sun_mesh={"stiffness": {0: ksp, 1: eps * ksp / 2 * np.exp(0.3j), 2: eps * ksp / 5},
                  "damping": 0.02 * np.sqrt(ksp * MASS["p"]),
                  "transmission_error": {1: te / 2} if te else None},
        ring_mesh={"stiffness": {0: krp, 1: eps * krp / 2 * np.exp(-0.7j)},
                   "damping": 0.01 * np.sqrt(krp * MASS["p"]),
                   "transmission_error": {1: te / 2 * np.exp(1j)} if te else None},
        planets=planets, frame=frame, **extra,
    )  # fmt: skip
    speed = carrier_speed / float(m.speed_plan().ratios["carrier"])
    return m, speed
