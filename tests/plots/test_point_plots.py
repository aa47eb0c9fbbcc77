"""The plots of one operating point: what they draw equals the results file's numbers (the
amplitudes 2|q_n|, the orbit's extent, the bearing's load and the solver's residual), and no
label overlaps another, no panel is empty (rheolin.plots.layout)."""

from __future__ import annotations

import numpy as np
import pytest

from rheolin.data import example_path
from rheolin.io import load_model
from rheolin.plots import point
from rheolin.plots.layout import problems
from rheolin.results import point_dataset, solve_point


@pytest.fixture(scope="module")
def rotor():
    """The rotor example at 3000 rpm: unbalance at 1x, a flat shaft (2x sidebands)."""
    return point_dataset(
        solve_point(load_model(example_path("rotor")), 100 * np.pi, stability=False)
    )


@pytest.fixture(scope="module")
def pair():
    """The preloaded gear pair: a static deflection far larger than its orbit, an axial-only
    joint (p_axial) and bearings carrying torsion only nowhere."""
    return point_dataset(solve_point(load_model(example_path("preloaded")), 100.0, stability=False))


def _amplitude(ds, node):
    q = ds["displacement"].sel(node=node, part="real") + 1j * ds["displacement"].sel(
        node=node, part="imag"
    )
    r = np.hypot(np.abs(q.sel(component="ux")), np.abs(q.sel(component="uy"))).values
    return np.where(ds["harmonic"].values > 0, 2 * r, r)


def test_spectrum_draws_the_largest_harmonics_at_their_amplitude(rotor):
    fig = point.spectrum_figure(rotor, ["rotor:1"])
    assert problems(fig) == []
    (ax,) = fig.axes
    x, y = ax.lines[0].get_data()  # the markers of the one node
    amp = _amplitude(rotor, "rotor:1")[1:] * 1e6  # oscillating harmonics [um]
    f = rotor["frequency"].values[1:]
    k = int(np.argmax(amp))
    assert float(np.max(y)) == pytest.approx(amp[k], rel=1e-12)
    assert float(x[int(np.argmax(y))]) == pytest.approx(f[k], rel=1e-12)
    assert np.all(np.asarray(y) >= 1e-3 * amp.max())  # 60 dB below the largest: left out
    assert ax.get_xscale() in ("log", "linear")


def test_orbit_is_drawn_about_the_static_position_at_its_true_size(pair):
    """The orbit's extent along x equals that of ux(t) summed from the file's harmonics over
    a period of the base frequency (every harmonic repeats in it), in the unit the axis
    names; the static deflection only in the title."""
    fig = point.orbits_figure(pair, ["p:1"])
    assert problems(fig) == []
    ax = fig.axes[0]
    x, _y = ax.lines[0].get_data()
    q = pair["displacement"].sel(node="p:1", component="ux")
    qn = (q.sel(part="real") + 1j * q.sel(part="imag")).values
    n = pair["harmonic"].values
    t = np.linspace(0.0, 2 * np.pi, 200001)  # w1 t over one base period
    ux = sum(2 * (qn[k] * np.exp(1j * n[k] * t)).real for k in range(n.size) if n[k] > 0)
    unit = ax.get_xlabel().split("[")[1].rstrip("]")
    scale = {"mm": 1e3, "µm": 1e6, "nm": 1e9}[unit]
    assert np.ptp(x) == pytest.approx(np.ptp(ux) * scale, rel=1e-3)
    assert abs(np.mean(x)) < 0.1 * np.ptp(x)  # centred on the static position
    static = float(pair["displacement"].sel(node="p:1", component="ux", part="real")[0]) * 1e6
    assert f"({static:.3g}," in ax.get_title()


def test_bearing_panels_show_what_each_joint_carries(pair):
    """p_axial carries an axial force only: its panel says so and draws 2|F_z|; no panel is
    a torsional moment of zero."""
    fig = point.bearing_spectra_figure(pair)
    assert problems(fig) == []
    titles = [ax.get_title() for ax in fig.axes if ax.get_visible()]
    assert "p_axial: axial force" in titles
    assert not any("torsional" in t for t in titles)
    ax = next(a for a in fig.axes if a.get_title() == "p_axial: axial force")
    F = pair["bearing_force"].sel(bearing="p_axial", force_component="Fz")
    fz = np.abs(F.sel(part="real") + 1j * F.sel(part="imag")).values[1:] * 2
    assert float(np.max(ax.lines[0].get_ydata())) == pytest.approx(fz.max(), rel=1e-12)


def test_convergence_marks_the_recomputed_backward_error(rotor):
    fig = point.convergence_figure(rotor)
    assert problems(fig) == []
    (ax,) = fig.axes
    star = [line for line in ax.lines if line.get_marker() == "*"]
    assert star and float(star[0].get_ydata()[0]) == pytest.approx(rotor.attrs["residual"])
    assert "backward error" in ax.get_ylabel()
    rtol = [line for line in ax.lines if line.get_linestyle() == ":"]
    assert float(rtol[0].get_ydata()[0]) == pytest.approx(rotor.attrs["rtol"])
