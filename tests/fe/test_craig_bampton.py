"""Craig-Bampton bodies against the unreduced FE model (eigsh shift-invert, direct solves)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import rheolin as rl
from rheolin.errors import ModelError
from rheolin.fe import CondensedFE, Coupling, condense, coupling_transform

pytest.importorskip("skfem")
from rheolin.fe.solid import solid_model, tensor_block

L, B, H = 0.3, 0.1, 0.06


@pytest.fixture(scope="module")
def bar():  # type: ignore[no-untyped-def]
    return solid_model(*tensor_block((L, B, H), (12, 4, 3)))


def _ends(fe, kind="average"):  # type: ignore[no-untyped-def]
    left = fe.nodes_where(lambda x: x[:, 0] < 1e-9)
    right = fe.nodes_where(lambda x: x[:, 0] > L - 1e-9)
    return [
        Coupling("left", left, [0.0, B / 2, H / 2], kind=kind),
        Coupling("right", right, [L, B / 2, H / 2], kind=kind),
    ]


def _full_modes(fe, couplings, k, fixed=None):  # type: ignore[no-untyped-def]
    """The unreduced FE model with the same couplings, by eigsh (shift-invert)."""
    T, free = coupling_transform(fe, couplings)
    if fixed is not None:
        keep = np.concatenate(
            [
                np.arange(6 * len(couplings)),
                6 * len(couplings) + np.flatnonzero(~np.isin(free, fixed)),
            ]
        )
        T = T[:, keep]
    Kt, Mt = sp.csc_array(T.T @ fe.K @ T), sp.csc_array(T.T @ fe.M @ T)
    lam = spla.eigsh(Kt, k=k, M=Mt, sigma=-1e4, which="LM", return_eigenvectors=False)
    return np.sort(np.sqrt(np.abs(lam)) / (2 * np.pi)), Kt, Mt


def _reduced_modes(body: CondensedFE) -> np.ndarray:
    lam = sla.eigh(body.K, body.M, eigvals_only=True)
    return np.sqrt(np.abs(lam)) / (2 * np.pi)


@pytest.mark.parametrize("kind", ["average", "rigid"])
def test_free_body_modes_match_the_full_model(bar, kind) -> None:  # type: ignore[no-untyped-def]
    full, _, _ = _full_modes(bar, _ends(bar, kind), 6 + 8)
    cutoff = full[-1]  # the eighth flexible mode
    body = condense(bar, None, _ends(bar, kind), modes=4, cutoff_hz=4 * cutoff)
    assert body.rigid_body_modes == 6
    red = _reduced_modes(body)
    # six exact rigid-body modes, then the flexible ones below the cut-off to 1e-3
    assert np.all(red[:6] < 1e-6 * full[6])
    flex = full[6:]
    np.testing.assert_allclose(red[6 : 6 + flex.size], flex, rtol=1e-3)
    assert np.allclose(body.M, body.M.T) and np.allclose(body.K, body.K.T)
    assert body.frequencies[-1] >= 4 * cutoff


def test_clamped_body_has_no_rigid_body_modes(bar) -> None:  # type: ignore[no-untyped-def]
    right = _ends(bar)[1:]
    fixed = bar.dofs_of(bar.nodes_where(lambda x: x[:, 0] < 1e-9))
    full, _, _ = _full_modes(bar, right, 6, fixed=fixed)
    cutoff = full[3]  # the modes of interest: the first four
    body = condense(bar, None, right, modes=4, cutoff_hz=6 * cutoff, fixed=fixed)  # 4x: 1.5e-3
    assert body.rigid_body_modes == 0
    np.testing.assert_allclose(_reduced_modes(body)[:4], full[:4], rtol=1e-3)


def _housing_model(body: CondensedFE) -> rl.Model:
    """A shaft on two bearings whose outer rings sit in the condensed body's seats."""
    m = rl.Model()
    m.add_shaft(
        "shaft",
        [0.0, 0.15, 0.3],
        outer_diameter=0.04,
        axis=(1, 0, 0),
        origin=(0.0, B / 2, H + 0.05),
        material_damping=1e-5,
        material="steel",
    )
    m.add_disk("shaft", 1, outer_diameter=0.2, width=0.03, material="steel")
    m.add_force("unbalance_y", "shaft", 1, force=(0, 100.0, 0), order=1)  # rotating load
    m.add_force("unbalance_z", "shaft", 1, force=(0, 0, 100.0), order=1, phase=-np.pi / 2)
    m.add_condensed_body("housing", body=body, speed_ratio=0)
    for i, (node, seat) in enumerate(((0, 0), (2, 1))):
        m.add_bearing(
            f"b{i}",
            "shaft",
            node,
            stiffness=[2e8, 2e8, 1e8, 0, 0, 0],
            damping=[800.0, 800.0, 400.0, 0, 0, 0],
            components=None,
            other_body="housing",
            other_node=seat,
        )
    m.add_bearing("torsion", "shaft", 0, stiffness=[1e4], damping=[1.0], components=["phix"])
    return m


def test_frequency_response_with_a_housing_matches_the_unreduced_assembly(bar) -> None:  # type: ignore[no-untyped-def]
    """Housing clamped at its bottom, bearing seats on its top: the assembly's unbalance
    response below the cut-off against the unreduced housing (every inner FE DOF kept)."""
    top = bar.nodes_where(lambda x: x[:, 2] > H - 1e-9)
    xs = bar.coordinates[top, 0]
    seats = [
        Coupling("seat0", top[xs < 0.05], [0.0, B / 2, H]),
        Coupling("seat1", top[xs > L - 0.05], [L, B / 2, H]),
    ]
    fixed = bar.dofs_of(bar.nodes_where(lambda x: x[:, 2] < 1e-9))
    D = 1e-6 * bar.K
    fe = type(bar)(bar.K, bar.M, bar.coordinates, bar.dof_node, bar.dof_component, D=D)
    body = condense(fe, None, seats, modes=10, fixed=fixed, cutoff_hz=40000.0)
    T, free = coupling_transform(fe, seats)
    keep = np.concatenate([np.arange(12), 12 + np.flatnonzero(~np.isin(free, fixed))])
    T = T[:, keep]
    red = {k: (T.T @ X @ T).toarray() for k, X in (("K", fe.K), ("M", fe.M), ("D", D))}
    full = CondensedFE(
        M=red["M"],
        K=red["K"],
        D=red["D"],
        interface=["seat0", "seat1"],
        positions=body.positions,
        frequencies=np.zeros(T.shape[1] - 12),
        rigid_body_modes=0,
    )
    for speed in (300.0, 2000.0, 6000.0):  # rad/s; the housing's first mode is far above
        q = {}
        for name, b in (("reduced", body), ("full", full)):
            a = _housing_model(b).assemble(speed)
            sol = rl.solve(
                a.system, rl.HarmonicSet.closure(a.system, order=1), method="lti", stability=False
            )
            assert sol.success, sol.message
            nodes = np.concatenate(
                [a.dofs("shaft", i) for i in range(3)] + [a.dofs("housing", i) for i in range(2)]
            )
            q[name] = sol.q[:, nodes]
        err = np.abs(q["reduced"] - q["full"]).max() / np.abs(q["full"]).max()
        assert err < 1e-3, (speed, err)


def test_saved_body_loads_from_a_model_file(bar, tmp_path) -> None:  # type: ignore[no-untyped-def]
    body = condense(bar, None, _ends(bar), modes=6)
    body.save(tmp_path / "bar.npz")
    toml = f"""
[model]
input_body = "rotor"
[[rigid_bodies]]
name = "rotor"
position = ["0 m", "0 m", "0 m"]
mass = "1 kg"
inertia = ["1 kg*m^2", "1 kg*m^2", "1 kg*m^2"]
[[condensed_bodies]]
name = "bar"
path = "{tmp_path / "bar.npz"}"
speed_ratio = 0
[[condensed_bodies.bearings]]
name = "a"
node = 0
components = "all"
stiffness = ["1e8 N/m", "1e8 N/m", "1e8 N/m", "1e5 N*m/rad", "1e5 N*m/rad", "1e5 N*m/rad"]
"""
    from rheolin.io import parse_model

    m = parse_model(toml, base=tmp_path).model
    a = m.assemble(1.0)
    assert a.system.n == 6 + 12 + body.n_modes
    dofs = np.concatenate([a.dofs("bar", 0), a.dofs("bar", 1), 18 + np.arange(body.n_modes)])
    np.testing.assert_allclose(a.system.M[0].toarray()[np.ix_(dofs, dofs)], body.M, atol=1e-12)
    with pytest.raises(ModelError, match="spin_axis"):
        m.bodies["bar"].speed_ratio = 1  # a spinning modal body needs its Coriolis matrices
        m.assemble(1.0)


def test_bad_interfaces_are_named(bar) -> None:  # type: ignore[no-untyped-def]
    line = bar.nodes_where(lambda x: (x[:, 1] < 1e-9) & (x[:, 2] < 1e-9))[:3]
    with pytest.raises(ModelError, match="collinear"):
        condense(bar, None, [Coupling("edge", line, [0, 0, 0])])
    with pytest.raises(ModelError, match="kind"):
        condense(bar, None, [Coupling("x", line, [0, 0, 0], kind="glue")])
    with pytest.raises(ModelError, match="interface"):
        condense(bar, None, [])


def _spinning_box():  # type: ignore[no-untyped-def]
    """A stiff steel box (E x 100) condensed with ``spin_axis`` on one averaged node at its
    centroid, on a 6-component bearing, turning about its own axis at W = 900 rad/s: the
    lowest six frequencies of the assembled (time-averaged) system and the rigid-body closed
    forms, translations ``sqrt(k/m)`` (x2), axial ``sqrt(kz/m)``, tilt whirl roots of
    ``Id w^2 -+ Ip W w - kr = 0``, torsion ``sqrt(kt/Ip)``."""
    a, c, rho = 0.1, 0.04, 7850.0
    fe = solid_model(*tensor_block((a, a, c), (4, 4, 3)), elastic_modulus=2.1e13,
                     poisson_ratio=0.3, density=rho)  # fmt: skip
    everything = np.arange(fe.coordinates.shape[0])
    body = condense(fe, None, [Coupling("hub", everything, [a / 2, a / 2, c / 2])], modes=6,
                    spin_axis=[0.0, 0.0, 1.0])  # fmt: skip
    m = rho * a * a * c
    ip, jd = m * (2 * a * a) / 12, m * (a * a + c * c) / 12
    k, kz, kr, kt = 1e7, 2e7, 4e4, 3e4
    model = rl.Model(input_body="box")
    model.add_condensed_body("box", body=body, speed_ratio=1)
    model.add_bearing("b", "box", 0, stiffness=np.diag([k, k, kz, kr, kr, kt]), components=None)
    W = 900.0
    s = model.assemble(W).system
    Mm, K = s.M[0].toarray(), s.K[0].toarray()
    D = s.D[0].toarray() if 0 in s.D else np.zeros_like(Mm)
    n = Mm.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)],
                  [-np.linalg.solve(Mm, K), -np.linalg.solve(Mm, D)]])  # fmt: skip
    got = np.sort(np.abs(np.linalg.eigvals(A).imag))[::2][:6]
    tilt = [(s_ * ip * W + np.sqrt((ip * W) ** 2 + 4 * jd * kr)) / (2 * jd) for s_ in (-1, 1)]
    closed = {
        "lateral": np.sqrt(k / m),
        "axial": np.sqrt(kz / m),
        "tilt": tilt,
        "torsion": np.sqrt(kt / ip),
    }
    return got, closed


def test_spinning_condensed_box_translates_as_the_closed_form() -> None:
    """The Coriolis and centrifugal terms of the translations cancel against the frame
    rotation (a sign error in the spin operator doubled them: whirl at sqrt(k/m) +- 2W)."""
    got, closed = _spinning_box()
    for want in (closed["lateral"], closed["lateral"], closed["axial"]):
        assert np.min(np.abs(got - want)) < 1e-6 * want, (got, want)


def test_spinning_condensed_box_tilts_and_twists_as_the_closed_form() -> None:
    """The rigid-body stress stiffening cancels the spin softening of the rotations (without
    it the torsion was sqrt((kt - W^2 Ip) / Ip), the tilt whirl softened by W^2 x the second
    moment along the axis)."""
    got, closed = _spinning_box()
    for want in [*closed["tilt"], closed["torsion"]]:
        assert np.min(np.abs(got - want)) < 1e-9 * want, (got, want)
