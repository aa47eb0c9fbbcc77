"""ROSS import (rheolin.io.ross): without ROSS from a file in ROSS's format, and against ROSS
2.3 itself (optional dev dependency) on its example rotors."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from rheolin.errors import ModelError
from rheolin.io.ross import model_from_ross
from rheolin.mechanics.model import Model
from rheolin.results.speeds import lti_speeds
from rheolin.stability.modes import averaged_modes

STEEL = {"name": "Steel", "rho": 7810.0, "E": 211e9, "G_s": 81.2e9, "color": "#525252"}

ROSS_TEXT = """
ross_version = "2.3.0"
[parameters]
["ShaftElement_0"]
L = 0.25
idl = 0.0
odl = 0.05
idr = 0.0
odr = 0.05
n = 0
["ShaftElement_1"]
L = 0.2
idl = 0.0
odl = 0.06
idr = 0.0
odr = 0.04
n = 1
["ShaftElement_2"]
L = 0.2
idl = 0.04
odl = 0.08
n = 1
["DiskElement_Disk 0"]
n = 1
m = 20.0
Id = 0.1
Ip = 0.2
["BearingElement_B0"]
n = 0
kxx = [1e6, 2e6, 4e6]
kxy = [1e5, 2e5, 2e5]
cxx = [100.0, 200.0, 300.0]
frequency = [100.0, 300.0, 500.0]
["SealElement_S1"]
n = 2
kxx = 3e6
cxx = 10.0
mxx = 0.5
["ShaftElement_0".material]
name = "Steel"
rho = 7810.0
E = 211000000000.0
G_s = 81200000000.0
["ShaftElement_1".material]
name = "Steel"
rho = 7810.0
E = 211000000000.0
G_s = 81200000000.0
["ShaftElement_2".material]
name = "Sleeve"
rho = 2700.0
E = 7e10
G_s = 2.6e10
"""


def test_file_without_ross_equals_the_model_built_by_hand(tmp_path):
    """A ROSS-format file (tapered element, a sleeve layer, a disk, a bearing table, a seal
    with added mass) gives exactly the model written with rheolin's own API."""
    path = tmp_path / "rotor.toml"
    path.write_text(ROSS_TEXT)
    got = model_from_ross(path)
    ref = Model()
    ref.add_shaft(
        "rotor",
        [0.0, 0.25, 0.45],
        outer_diameter=[0.05, 0.06],
        outer_diameter_right=[0.05, 0.04],
        elastic_modulus=211e9,
        shear_modulus=81.2e9,
        density=7810.0,
    )
    ref.add_shaft_layer(
        "rotor", [1], 0.08, 0.04, elastic_modulus=7e10, shear_modulus=2.6e10, density=2700.0
    )
    ref.add_disk("rotor", 1, mass=20.0, inertia=np.diag([0.1, 0.1, 0.2]))
    from scipy.interpolate import interp1d  # ROSS's interpolant for three speeds

    for W in (150.0, 420.0):
        kxx = float(interp1d([100.0, 300.0, 500.0], [1e6, 2e6, 4e6], kind=2)(W))
        kxy = float(interp1d([100.0, 300.0, 500.0], [1e5, 2e5, 2e5], kind=2)(W))
        cxx = float(interp1d([100.0, 300.0, 500.0], [100.0, 200.0, 300.0], kind=2)(W))
        m = Model()
        m.bodies, m.joints = dict(ref.bodies), {}
        m.add_bearing(
            "b",
            "rotor",
            0,
            [[kxx, kxy, 0], [0, kxx, 0], [0, 0, 0]],
            [[cxx, 0, 0], [0, cxx, 0], [0, 0, 0]],
            ["ux", "uy", "uz"],
        )
        m.add_bearing("s", "rotor", 2, 3e6, 10.0, mass=0.5)
        a, b = got.assemble(W).system, m.assemble(W).system
        for X in "MDK":
            x, y = getattr(a, X)[0].toarray(), getattr(b, X)[0].toarray()
            assert np.abs(x - y).max() <= 1e-12 * np.abs(y).max(), (W, X)


def test_unsupported_features_are_refused_by_name():
    import tomllib

    doc = tomllib.loads(ROSS_TEXT)
    doc["ShaftElement_1"]["axial_force"] = 1e3
    with pytest.raises(ModelError, match=r"ShaftElement_1\.axial_force"):
        model_from_ross(doc)
    doc = tomllib.loads(ROSS_TEXT)
    doc["MagneticBearingElement_0"] = {"n": 0}
    with pytest.raises(ModelError, match="MagneticBearingElement"):
        model_from_ross(doc)


# ------------------------------------------------------------------ against ROSS itself
@pytest.fixture(scope="module")
def rs():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return pytest.importorskip("ross")


def _matrices(rotor, model, W):
    s = model.assemble(W).system
    ours = [s.M[0].toarray(), s.D[0].toarray(), s.K[0].toarray()]
    theirs = [rotor.M(W), rotor.C(W) + W * rotor.G(), rotor.K(W)]
    return max(np.abs(x - y).max() / np.abs(y).max() for x, y in zip(ours, theirs, strict=True))


def _frequencies(rotor, model, W, k=8):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        theirs = np.sort(rotor.run_modal(W, num_modes=2 * k + 8).wd)
    f = averaged_modes(model.assemble(W).system).frequency
    ours = np.sort(f[(f > 1e-3) & (np.abs(f - 1.0) > 1e-6)])  # free axial/torsion, point masses
    theirs = theirs[theirs > 1e-3]
    return np.abs(ours[:k] - theirs[:k]).max() / theirs[:k].max()


def _unbalance(rotor, model, node, speeds):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        X = np.asarray(rotor.run_unbalance_response([node], [1e-3], [0.3], speeds).forced_resp)
    t = model.speed_template()

    def load(w, n):
        f = np.zeros((w.size, t.n_dof), complex)
        f[:, 6 * node] = 1e-3 * w**2 / 2 * np.exp(0.3j)
        f[:, 6 * node + 1] = -0.5j * 1e-3 * w**2 * np.exp(0.3j)
        return f

    r = lti_speeds(t, speeds, [1], loads=load)
    assert r.success.all()
    return np.abs(2 * r.q[:, 0].T - X[: t.n_dof]).max() / np.abs(X).max()


def test_rotor_example_matches_ross(rs, tmp_path):
    """rotor_example (free axial and torsional DOFs), read back from the file ROSS saved."""
    rotor = rs.rotor_example()
    path = tmp_path / "rotor.toml"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rotor.save(path)
    model = model_from_ross(path)
    assert _matrices(rotor, model, 300.0) < 1e-14
    assert _frequencies(rotor, model, 300.0) < 1e-10
    assert _unbalance(rotor, model, 2, np.linspace(20.0, 800.0, 9)) < 1e-10


def test_compressor_example_matches_ross(rs):
    """compressor_example: sleeve layers, 11 seals and 2 bearings with speed tables."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rotor = rs.compressor_example()
    model = model_from_ross(rotor)
    for W in (100.0, 700.0, 1000.0):  # below (extrapolated), inside and between table speeds
        assert _matrices(rotor, model, W) < 1e-13
    assert _frequencies(rotor, model, 700.0) < 1e-8
    assert _unbalance(rotor, model, 20, np.linspace(300.0, 1200.0, 7)) < 1e-9


def test_tapered_point_mass_and_linked_bearing_match_ross(rs):
    from ross.materials import steel

    sh = [rs.ShaftElement(L=0.25, idl=0, odl=0.05, material=steel, n=i) for i in range(4)]
    sh.append(rs.ShaftElement(L=0.2, idl=0, odl=0.06, idr=0.01, odr=0.04, material=steel, n=4))
    disks = [rs.DiskElement(n=2, m=20.0, Id=0.1, Ip=0.2)]
    brg = [
        rs.BearingElement(n=0, n_link=6, kxx=1e7, kyy=2e7, cxx=1e3, kzz=1e6),
        rs.BearingElement(n=6, kxx=1e6, cxx=50.0, kzz=1e6),
        rs.BearingElement(
            n=5,
            kxx=[1e6, 3e6, 4e6, 4.5e6, 6e6],
            kxy=[1e5, 2e5, 3e5, 3e5, 2e5],
            cxx=[1e2, 2e2, 3e2, 3e2, 3e2],
            mxx=[0.1, 0.2, 0.2, 0.3, 0.3],
            frequency=[10.0, 200.0, 400.0, 600.0, 900.0],
        ),
    ]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rotor = rs.Rotor(sh, disks, brg, [rs.PointMass(n=6, m=3.0)])
    model = model_from_ross(rotor)
    for W in (150.0, 500.0):
        assert _frequencies(rotor, model, W) < 1e-10
