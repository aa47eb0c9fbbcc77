"""Planetary sets through ``Model.add_planetary``: the model equals the term-level set that
test_planetary.py validates against Lin & Parker's model, outputs do not depend on the frame
the set is written in, and bad sets are refused naming the field."""

from __future__ import annotations

import json

import numpy as np
import pytest
from planetary_cases import build, model_case

import rheolin as rl
from rheolin.errors import ModelError
from rheolin.results.frf import frequency_response, system_frequency_response
from rheolin.results.outputs import (
    bearing_force_array,
    global_displacements,
    transmission_error_array,
)


@pytest.mark.parametrize(("frame", "members"), [("carrier", "carrier"), ("inertial", "inertial")])
def test_model_set_is_the_validated_set(frame, members):
    m, speed = model_case(eps=0.3, frame=frame)
    a = m.assemble(speed)
    ref = build(eps=0.3, members=members).system
    assert a.omega == pytest.approx(ref.omega)
    for name in "MDK":
        A, B = getattr(a.system, name), getattr(ref, name)
        assert set(A) == set(B)
        scale = max(abs(B[k]).max() for k in B)
        for k in B:
            assert abs(A[k] - B[k]).max() <= 1e-14 * scale


def test_outputs_do_not_depend_on_the_frame():
    """The same set under gravity and transmission error, solved with its members in the
    carrier frame and in global axes: displacements (turned back to global axes), bearing
    forces on the supports and every mesh's dynamic transmission error agree."""
    out = {}
    for frame in ("carrier", "inertial"):
        m, speed = model_case(eps=0.2, te=1e-3, frame=frame, out_damping=20.0)
        m.set_gravity((0.0, -1.0, 0.0))  # scaled model: loads of the transmission error's size
        a = m.assemble(speed)
        H = rl.HarmonicSet.closure(a.system, order=3, generators=a.generators)
        sol = rl.solve(a.system, H, method="gmres", stability=False)
        assert sol.success
        out[frame] = (a, sol)
    (a1, s1), (a2, s2) = out["carrier"], out["inertial"]
    common = np.intersect1d(s1.harmonics[s1.harmonics >= 0], s2.harmonics[s2.harmonics >= 0])
    i1 = np.searchsorted(s1.harmonics[s1.harmonics >= 0], common)
    i2 = np.searchsorted(s2.harmonics[s2.harmonics >= 0], common)
    q1, q2 = global_displacements(s1, a1)[i1], global_displacements(s2, a2)[i2]
    assert np.abs(q1).max() > 0
    assert np.abs(q1 - q2).max() < 1e-6 * np.abs(q1).max()
    for name in a1.joints:
        f1 = bearing_force_array(s1, a1, name)[1][i1]
        f2 = bearing_force_array(s2, a2, name)[1][i2]
        assert np.abs(f1 - f2).max() < 1e-6 * np.abs(f1).max(), name
    for name in a1.meshes:
        d1 = transmission_error_array(s1, a1, name)[1][i1]
        d2 = transmission_error_array(s2, a2, name)[1][i2]
        assert np.abs(d1 - d2).max() < 1e-6 * np.abs(d1).max(), name


def _set(m=None, **kw):
    """A small set (sun input, ring held) with ``kw`` replacing add_planetary's arguments."""
    from rheolin.mechanics.model import Model

    if m is None:
        m = Model(input_body="sun")
        for name, ratio in (("sun", None), ("ring", 0), ("carrier", None)):
            m.add_rigid_body(name, (0, 0, 0), 2.0, (0.1, 0.1, 0.2), speed_ratio=ratio)
            m.add_bearing(f"{name}_b", name, 0, 1e8, 10.0, components=None)
    args = dict(
        name="set", sun_body="sun", sun_node=0, ring_body="ring", ring_node=0,
        carrier_body="carrier", carrier_node=0, sun_teeth=20, planet_teeth=20, ring_teeth=60,
        module=0.003, planets=4, planet={"mass": 0.5, "inertia": [1e-3, 1e-3, 2e-3]},
        planet_bearing={"stiffness": [1e8, 1e8, 1e8, 1e5, 1e5]},
        sun_mesh={"stiffness": 3e8}, ring_mesh={"stiffness": 4e8},
    )  # fmt: skip
    args.update(kw)
    m.add_planetary(**{k: v for k, v in args.items() if v is not ...})
    return m


def test_frf_in_global_axes_does_not_depend_on_the_frame():
    """Receptances between inertial forces and displacements of the sun, ring and carrier
    (phased parametric meshes, carrier at 20 rad/s): with the members written in the carrier's
    axes (inputs through ``T^T`` on the sidebands +-W_c, outputs turned back) equal to the set
    with inertial members, where no turning is needed; the carrier-frame receptance itself
    differs (the forces turn there)."""
    w = 2 * np.pi * np.array([8.0, 10.0, 21.0, 27.0, 40.0])
    dofs = ["sun:0:ux", "sun:0:uy", "ring:0:uy", "carrier:0:ux"]
    res = {}
    for frame in ("carrier", "inertial"):
        m, speed = model_case(carrier_speed=20.0, frame=frame, eps=0.3)
        res[frame] = frequency_response(m, speed, w, dofs[::2], dofs, order=3).receptance
    ref = np.abs(res["inertial"]).max()
    assert np.abs(res["carrier"] - res["inertial"]).max() < 1e-9 * ref
    m, speed = model_case(carrier_speed=20.0, eps=0.3)
    a = m.assemble(speed)
    sun = a.dof_labels.index(("sun", 0, "ux"))
    turning = system_frequency_response(a.system, w, [sun], order=3).receptance[:, 0, 0]
    assert np.abs(turning - res["inertial"][:, 0, 0]).max() > 0.1 * ref


@pytest.mark.parametrize(
    ("kw", "field"),
    [
        ({"planets": 3}, "`ring_teeth`: 3 equally spaced planets do not assemble"),
        ({"ring_teeth": 58}, "`ring_teeth`: 58 teeth: a ring smaller than the sun plus two"),
        ({"planets": ..., "planet_angles": np.radians([0, 45, 180])}, "planets 0 and 1 .* collide"),
        ({"planets": ..., "planet_angles": [0.0, 0.6, 3.0]}, r"`planet_angles\[1\]`: 34.3775 deg"),
        ({"planet_angles": [0.0, np.pi]}, "give `planets` .* or `planet_angles`, one of them"),
        ({"sun_mesh": {"stifness": 3e8}}, "`sun_mesh.stifness` is not a key"),
        (
            {"planet_bearing": {"stiffness": [1e8, 1e8], "components": ["ux", "uy"]}},
            "`planet_bearing.stiffness`: the planets need a positive stiffness on uz",
        ),
        ({"frame": "ring"}, "`frame` must be one of"),
        ({"ring_body": "sun"}, "must be three bodies"),
        ({"pin_errors": [[0, 1e-5]]}, "`pin_errors` needs one"),
    ],
)
def test_bad_sets_are_refused_naming_the_field(kw, field):
    with pytest.raises(ModelError, match=field):
        _set(**kw)


def test_a_set_nothing_holds_is_refused():
    from rheolin.mechanics.model import Model

    m = Model(input_body="sun")
    for name in ("sun", "ring", "carrier"):
        m.add_rigid_body(name, (0, 0, 0), 2.0, (0.1, 0.1, 0.2))
        m.add_bearing(f"{name}_b", name, 0, 1e8, 10.0, components=None)
    _set(m)
    with pytest.raises(ModelError, match=r"does not determine the speeds of .*planetary set"):
        m.assemble(100.0)


def test_load_dependent_bearing_in_the_carrier_frame_is_refused():
    m = _set()
    m.add_rolling_bearing("rb", "carrier", 0, law="radial", stiffness=1e10)
    with pytest.raises(ModelError, match="rolling bearing 'rb': body 'carrier' is in the carrier"):
        m.assemble(100.0)
    m = _set(frame="inertial")
    m.add_rolling_bearing("rb", "carrier", 0, law="radial", stiffness=1e10)
    m.assemble(100.0)  # inertial members may carry one


def test_load_sharing_under_torque_with_a_pin_error():
    """``Model.load_sharing`` (the static equilibrium under a sun torque, a 20 um tangential
    pin error on planet 0, the planets' orbit) against the reference's static carrier-frame
    solution; without the error the four planets share equally."""
    err = [[0.0, 20e-6], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]
    m, speed = model_case(pin_errors=err, scale=1.0, carrier_speed=50.0)
    m.add_torque("drive", "sun", 0, 200.0)
    ls = m.load_sharing(speed)["set"]
    case = build(pin_errors=tuple(np.array(e) for e in err), sun_torque=200.0, scale=1.0,
                 carrier_speed=50.0)  # fmt: skip
    ref = case.reference
    _, _, K, f = ref.matrices(0.0, case.carrier_speed)
    u = np.linalg.solve(K, f)
    gs, gr, _ = ref.gradients()
    k_s, k_r = ref.ks(0.0), ref.kr(0.0)
    assert np.allclose(ls.sun, [k_s[n] * gs[n] @ u for n in range(4)], rtol=1e-9)
    assert np.allclose(ls.ring, [k_r[n] * gr[n] @ u for n in range(4)], rtol=1e-9)
    assert ls.factor > 1.5
    m, speed = model_case(scale=1.0, carrier_speed=50.0)
    m.add_torque("drive", "sun", 0, 200.0)
    even = m.load_sharing(speed)["set"]
    assert even.factor == pytest.approx(1.0, abs=1e-9)
    r_bs = build(scale=1.0).geometry.base_radius(12)
    # the sun torque reaches the meshes (the sun's own torsional support takes its share)
    assert 0 < even.sun.sum() * r_bs < 200.0


def test_wind_turbine_example_at_rated_speed():
    """The example's rated point: the steady state converges, the verdict is decided stable,
    the three planets' sun meshes deflect alike at the mesh frequency (21 sun teeth on 3 equally
    spaced planets: in phase, a rotational excitation), and the planetary mesh frequency is the
    ring's 99 teeth times the rotor speed."""
    from rheolin.data import example_path
    from rheolin.io import read_model
    from rheolin.results import solve_point

    lm = read_model(example_path("wind-turbine"))
    h = lm.spec.harmonics
    speed = 22.1 * np.pi / 30
    p = solve_point(lm.model, speed, order=h.order, max_order=h.max_order)
    assert p.solution.success and p.solution.stable
    assert p.solution.floquet.decided
    a = p.assembled
    assert a.plan.sets["stage1"] * a.omega == pytest.approx(99 * speed, rel=1e-12)
    n, _ = transmission_error_array(p.solution, a, "stage1.sun0")
    at = np.searchsorted(n, a.plan.sets["stage1"])
    d = [transmission_error_array(p.solution, a, f"stage1.sun{k}")[1][at] for k in range(3)]
    assert abs(d[0]) > 1e-7
    assert d[1] == pytest.approx(d[0], rel=1e-6) and d[2] == pytest.approx(d[0], rel=1e-6)


def test_planet_orbit_plot_spans_one_carrier_revolution():
    """The orbit plot of a planet spans its orbit, one turn of the carrier (20 rad/s here),
    not the base period of the whole train."""
    from rheolin.plots.point import orbits_figure
    from rheolin.results import point_dataset, solve_point

    m, speed = model_case(carrier_speed=20.0, te=1e-6)
    ds = point_dataset(solve_point(m, speed, stability=False))
    orbits = json.loads(ds.attrs["orbits_json"])
    assert orbits == pytest.approx({f"set.planet{n}": 20.0 / (2 * np.pi) for n in range(4)})
    ax = orbits_figure(ds, ["set.planet1:0"]).axes[0]
    assert "one orbit of set.planet1" in ax.get_title()
    line = ax.get_lines()[0]  # the orbit: a closed curve over exactly one carrier turn
    xy = np.column_stack(line.get_data())
    assert np.abs(xy[-1] - xy[0]).max() < 1e-9 * np.abs(xy).max()
