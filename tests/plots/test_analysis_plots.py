"""The plots over speed and of modes: Campbell, mode shapes, Bode, run-up, stability map and
parameter study. Each is checked by rheolin.plots.layout (no overlapping label, no empty
panel, no legend entry without its artist) and against what it must show: the forward
branches of a gyroscopic rotor rise with speed, the SDOF peak and its half-power AF, the
asymmetric band between sqrt(k_x/m) and sqrt(k_y/m)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import rheolin as rl
from rheolin.plots import stability as stability_plot
from rheolin.plots.campbell import campbell_figure
from rheolin.plots.frf import bode_figure
from rheolin.plots.layout import problems
from rheolin.plots.modes import WHIRL_COLOURS, mode_shapes_figure
from rheolin.plots.study import parameter_figure
from rheolin.plots.sweep import sweep_figure
from rheolin.results.frf import system_frequency_response
from rheolin.results.sweep import sweep_speeds
from rheolin.stability import campbell, stability_map

sys.path.insert(0, str(Path(__file__).parents[1] / "report"))
from report_cases import study_cases

BAND, band_model = study_cases().BAND, study_cases().band_model


def overhung() -> rl.Model:
    """A shaft on isotropic bearings with a heavy disk: gyroscopic forward/backward pairs."""
    m = rl.Model()
    m.add_shaft("s", np.linspace(0, 0.6, 7), outer_diameter=0.04, material="steel")
    m.add_disk("s", 5, outer_diameter=0.3, width=0.04, material="steel", unbalance=1e-5)
    for k in (0, 3):
        m.add_bearing(f"b{k}", "s", k, stiffness=[2e7, 2e7, 1e8, 1e4], damping=200.0,
                      components=["ux", "uy", "uz", "phiz"])  # fmt: skip
    return m


def test_campbell_colours_forward_branches_that_rise_with_speed():
    """Gyroscopic stiffening: forward whirl rises with speed, backward falls. The points the
    plot colours blue (whirl ratio > 0.5) must sit on rising branches."""
    r = campbell(overhung(), np.linspace(0, 1500, 7))
    fig = campbell_figure(r)
    assert problems(fig) == []
    freq = r.frequency
    rising = np.nanmin(np.diff(freq, axis=0), axis=0) > 0
    forward = np.nanmin(r.whirl_ratio[1:], axis=0) > 0.5
    lateral = np.array([str(k).startswith("lateral") for k in r.kind[-1]])
    assert np.any(forward & lateral)
    assert np.all(rising[forward & lateral])
    top = fig.axes[0]
    blue = np.array([0.121, 0.466, 0.705])  # the map's +1 end, #1f77b4
    colours = np.concatenate(
        [c.get_facecolors()[:, :3] for c in top.collections if len(c.get_offsets())]
    )
    assert np.any(np.all(np.abs(colours - blue) < 0.02, axis=1))
    labels = [t.get_text() for legend in fig.legends for t in legend.get_texts()]
    assert all(name in labels for name in r.orders)


def test_mode_shapes_draw_forward_orbits_blue_and_backward_red():
    m = overhung()
    fig = mode_shapes_figure(m, 1000.0, n_modes=12)
    assert problems(fig) == []
    panels = [ax for ax in fig.axes if ax.get_visible()]
    assert len(panels) == 12
    for ax in panels:
        kind = ax.get_title().split("\n")[1]
        colours = {line.get_color() for line in ax.lines[1:]}  # the orbits after the line
        if kind == "lateral forward":
            assert WHIRL_COLOURS["forward"] in colours and WHIRL_COLOURS["backward"] not in colours
        if kind == "lateral backward":
            assert WHIRL_COLOURS["backward"] in colours and WHIRL_COLOURS["forward"] not in colours


def test_bode_marks_the_sdof_peak_with_its_half_power_af():
    """m = 1, k = 4, c = 0.2: zeta = 0.05, peak at w_n sqrt(1 - 2 zeta^2), AF ~ 1 / (2 zeta)."""
    s = rl.PeriodicSystem(1.0, M={0: np.eye(1)}, D={0: 0.2 * np.eye(1)}, K={0: 4 * np.eye(1)})
    w = np.linspace(0.5, 4.0, 3501)
    fig = bode_figure(system_frequency_response(s, w, inputs=[0]))
    assert problems(fig) == []
    ax = fig.axes[0]
    (text,) = [t.get_text() for t in ax.texts if t.get_visible()]
    f_peak = 2.0 * np.sqrt(1 - 2 * 0.05**2) / (2 * np.pi)
    assert float(text.split(" Hz")[0]) == pytest.approx(f_peak, rel=1e-3)
    assert float(text.split("AF ")[1]) == pytest.approx(10.0, rel=0.02)
    assert "[m/N]" in ax.get_ylabel()


@pytest.fixture(scope="module")
def band_sweep():
    speeds = np.linspace(90.0, 120.0, 13)
    return sweep_speeds(band_model(), speeds, order=2), stability_map(band_model(), speeds)


def test_run_up_plot_draws_each_body_response_and_shades_the_band(band_sweep):
    ds, smap = band_sweep
    ranges = [(r.lower * 30 / np.pi, r.upper * 30 / np.pi) for r in smap.ranges]
    fig = sweep_figure(ds, ranges)
    assert problems(fig) == []
    top = fig.axes[0]
    osc = ds["harmonic"] > 0
    ref = ds["response"].where(osc, 0.0).sum("harmonic").max("node").values * 1e6
    np.testing.assert_allclose(top.lines[0].get_ydata(), ref, rtol=1e-12)
    (lo, hi) = ranges[0]
    assert lo == pytest.approx(100 * 30 / np.pi, rel=1e-4)
    assert hi == pytest.approx(110 * 30 / np.pi, rel=1e-4)


def test_stability_map_legend_lists_only_what_is_drawn(band_sweep, monkeypatch):
    _, smap = band_sweep
    captured = []
    monkeypatch.setattr(stability_plot, "save", lambda fig, path: captured.append(fig))
    stability_plot.plot_stability(smap, "unused.png")
    (fig,) = captured
    assert problems(fig) == []
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "unstable" in labels  # the band's speeds are drawn red
    stable = stability_map(band_model(ky=1e4), np.linspace(90.0, 120.0, 4))
    stability_plot.plot_stability(stable, "unused.png")
    labels = [t.get_text() for t in captured[-1].axes[0].get_legend().get_texts()]
    assert "unstable" not in labels and problems(captured[-1]) == []


def test_study_plot_has_no_empty_panel(tmp_path):
    """With the band (k_y = 1.21e4) the lower panel shows it; with k_y = k_x = 1e4 there is
    none, and the figure has one panel whose title says so."""
    from rheolin.study import StudySpec, run_study

    path = tmp_path / "band.toml"
    path.write_text(BAND)
    speeds = np.linspace(95.0, 115.0, 6)
    for values, panels in (("1.1e4,1.21e4 N/m", 2), ("1e4,1.0001e4 N/m", 1)):
        spec = StudySpec.create(path, speeds, {"bearings.spring.stiffness[1]": values})
        result = run_study(spec, workers=1)
        fig = parameter_figure(result, "bearings.spring.stiffness[1]")
        assert problems(fig) == []
        assert len([a for a in fig.axes if a.get_label() != "<colorbar>"]) == panels
        if panels == 1:
            assert "no unstable range" in fig.axes[0].get_title()


def test_campbell_hatches_undecided_speeds_and_does_not_call_them_stable():
    """A map with one undecided speed: hatched in both panels and counted in the title,
    which must not say "stable at every speed" (a decided map of the same speeds does)."""
    from rheolin.stability.stability_map import StabilityMap

    r = campbell(overhung(), np.linspace(0, 1500, 7))
    n = r.speeds.size

    def smap(decided: np.ndarray) -> StabilityMap:
        ones = np.ones(n, dtype=bool)
        state = np.where(decided, "stable", "undecided")
        return StabilityMap(r.speeds, -np.ones(n), np.full(n, 1e-6), state == "stable", ~ones,
                            ones, np.zeros(n), decided=decided, state=state)  # fmt: skip

    some = np.ones(n, dtype=bool)
    some[3] = False
    fig = campbell_figure(r, stability=smap(some))
    assert problems(fig) == []
    title = fig.axes[0].get_title()
    assert "1 speed(s) undecided" in title and "stable at every speed" not in title
    hatched = [p for ax in fig.axes[:2] for p in ax.patches if p.get_hatch() == "///"]
    assert len(hatched) == 2
    clean = campbell_figure(r, stability=smap(np.ones(n, dtype=bool)))
    assert "stable at every speed" in clean.axes[0].get_title()
