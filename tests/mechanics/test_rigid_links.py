"""Exact rigid links (eliminated constraints) against independent references.

* Two rigid bodies welded by a link, on one 6-component bearing: the frequencies of the one
  composite rigid body (parallel-axis theorem: mass ``m1 + m2``, first moment ``m2 r``,
  inertia ``J1 + J2 + m2 (r.r I - r r^T)``) at standstill.
* A disk carried on a link from its shaft node against the same disk put there by
  ``axial_offset`` (its own exact lever, another code path): unbalance response, Floquet
  exponent, modes and FRF agree to round-off, where the linked disk once needed a short
  massless connecting element that broke the solve, Floquet and modes.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

import rheolin as rl
from rheolin.errors import ModelError
from rheolin.mechanics import Model
from rheolin.results import solve_point
from rheolin.results.frf import frequency_response
from rheolin.stability.modes import averaged_modes


def _skew(r: np.ndarray) -> np.ndarray:
    return np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0.0]])


def test_welded_bodies_move_as_the_composite_rigid_body() -> None:
    m1, m2, L = 5.0, 3.0, 0.4
    # axisymmetric bodies: a spinning body's time-averaged inertia is its own
    J1, J2 = np.diag([0.2, 0.2, 0.3]), np.diag([0.05, 0.05, 0.08])
    k = np.diag([1e6, 2e6, 3e6, 4e4, 5e4, 6e4])
    model = Model()
    model.add_rigid_body("a", (0, 0, 0), m1, np.diag(J1))
    model.add_rigid_body("b", (0.1, 0.0, L), m2, np.diag(J2), speed_ratio=1)
    model.add_bearing("k", "a", 0, k, components=None)
    model.add_rigid_link("weld", "a", 0, "b", 0)
    got = np.sort(averaged_modes(model.assemble(1e-9).system).frequency)
    r = np.array([0.1, 0.0, L])
    Mc = np.zeros((6, 6))
    Mc[:3, :3] = (m1 + m2) * np.eye(3)
    Mc[:3, 3:] = -m2 * _skew(r)  # translation of the composite centre by phi x r
    Mc[3:, :3] = Mc[:3, 3:].T
    Mc[3:, 3:] = J1 + J2 + m2 * (r @ r * np.eye(3) - np.outer(r, r))
    ref = np.sort(np.sqrt(sla.eigh(k, Mc, eigvals_only=True)))
    np.testing.assert_allclose(got, ref, rtol=1e-9)


def _rotor(linked: bool) -> Model:
    m = Model()
    m.add_shaft("s", np.linspace(0.0, 0.6, 4), outer_diameter=0.04, material="steel")
    for node in (0, 3):
        m.add_bearing(f"b{node}", "s", node, stiffness=[2e7, 1.5e7], damping=300.0)
    if linked:
        m.add_rigid_body("disk", (0.0, 0.0, 0.75), 8.0, (0.06, 0.06, 0.1), speed_ratio=1)
        m.add_disk("disk", 0, unbalance=2e-4)
        m.add_rigid_link("hub", "s", 3, "disk", 0)
    else:
        m.add_disk("s", 3, mass=8.0, inertia=[0.06, 0.06, 0.1], unbalance=2e-4,
                   axial_offset=0.15)  # fmt: skip
    return m


def test_linked_overhung_disk_equals_the_offset_disk() -> None:
    W = 2000 * np.pi / 30
    a, b = solve_point(_rotor(True), W), solve_point(_rotor(False), W)
    assert a.solution.success and b.solution.success
    qa = a.solution.harmonic(1)[a.assembled.dofs("s", 3)]
    qb = b.solution.harmonic(1)[b.assembled.dofs("s", 3)]
    assert np.abs(qa - qb).max() < 1e-9 * np.abs(qb).max()
    # the disk's own node follows the shaft end rigidly
    r = np.array([0.0, 0.0, 0.15])
    disk = a.solution.harmonic(1)[a.assembled.dofs("disk", 0)]
    np.testing.assert_allclose(
        disk[:3], qa[:3] + np.cross(qa[3:], r), atol=1e-12 * np.abs(qa).max()
    )
    fa = rl.floquet(a.assembled.system)
    fb = rl.floquet(b.assembled.system)
    assert fa.decided and fb.decided and fa.stable and fb.stable
    w1 = a.assembled.system.omega
    for lam in fb.exponents:  # the same exponents (imaginary parts modulo w1)
        d = fa.exponents - lam
        d = d.real + 1j * (d.imag - w1 * np.round(d.imag / w1))
        assert np.abs(d).min() < 1e-8 * max(abs(lam), w1)
    ma = averaged_modes(a.assembled.system).frequency
    mb = averaged_modes(b.assembled.system).frequency
    np.testing.assert_allclose(ma[:8], mb[:8], rtol=1e-9)
    w = np.linspace(50.0, 1500.0, 30)
    Ha = frequency_response(_rotor(True), W, w, inputs=["s:3:ux"]).receptance
    Hb = frequency_response(_rotor(False), W, w, inputs=["s:3:ux"]).receptance
    # the paths differ by the unbalance's second-order terms, which a rigid node leaves out
    # about its own node: (e / 0.15 m)^2 = 2.8e-8 (the difference scales as U^2, and is
    # 2e-14 without unbalance)
    assert np.abs(Ha - Hb).max() < 1e-7 * np.abs(Hb).max()


def test_bad_links_are_refused_naming_them() -> None:
    m = Model()
    for name, z in (("a", 0.0), ("b", 0.1), ("c", 0.2)):
        m.add_rigid_body(name, (0, 0, z), 1.0, (1.0, 1.0, 1.0))
    m.add_bearing("k", "a", 0, 1e6, components=None)
    with pytest.raises(ModelError, match="two different nodes"):
        m.add_rigid_link("self", "a", 0, "a", 0)
    with pytest.raises(ModelError, match="components"):
        m.add_rigid_link("bad", "a", 0, "b", 0, components=["ux", "rx"])
    m.add_rigid_link("ab", "a", 0, "b", 0)
    m.add_rigid_link("bc", "b", 0, "c", 0)  # a chain: c follows b follows a
    c = m.assemble(1.0).system.constraint
    assert c.pivots.size == 12 and np.all(c.keep == np.arange(6))
    m.add_rigid_link("again", "a", 0, "c", 0, components=["ux"])
    with pytest.raises(ModelError, match="'bc' and 'again' both constrain c node 0 ux"):
        m.assemble(1.0)
    loop = Model()
    for name, z in (("a", 0.0), ("b", 0.1)):
        loop.add_rigid_body(name, (0, 0, z), 1.0, (1.0, 1.0, 1.0))
    loop.add_rigid_link("ab", "a", 0, "b", 0, components=["ux"])
    loop.add_rigid_link("ba", "b", 0, "a", 0, components=["ux"])
    with pytest.raises(ModelError, match="loop"):
        loop.assemble(1.0)


def test_rigid_links_in_the_model_file_round_trip() -> None:
    from rheolin.io import parse_model

    text = """
[model]
input_body = "a"
[[rigid_bodies]]
name = "a"
position = [0, 0, 0]
mass = "5 kg"
inertia = [0.2, 0.2, 0.3]
[[rigid_bodies.bearings]]
name = "k"
node = 0
components = "all"
stiffness = [1e6, 1e6, 1e6, 1e4, 1e4, 1e4]
[[rigid_bodies]]
name = "b"
position = ["0 mm", "0 mm", "400 mm"]
mass = "3 kg"
inertia = [0.05, 0.05, 0.08]
speed_ratio = "1"
[[rigid_links]]
name = "weld"
body = "a"
node = 0
other_body = "b"
other_node = 0
"""
    model = parse_model(text).model
    again = parse_model(model.to_toml()).model
    ca, cb = (m.assemble(10.0).system.constraint for m in (model, again))
    assert np.array_equal(ca.pivots, cb.pivots) and np.array_equal(ca.G, cb.G)
    assert ca.G[2, 4] == 0 and ca.G[0, 4] == pytest.approx(0.4)  # ux_b = ux_a + 0.4 phiy_a
    twice = text + text[text.index("[[rigid_links]]") :].replace('"weld"', '"again"')
    with pytest.raises(ModelError, match=r"rigid_links.*'weld' and 'again'"):
        parse_model(twice)
