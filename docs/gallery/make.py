"""Make docs/gallery.md: every figure rheolin draws, from the embedded examples, each checked
for overlapping labels, empty panels and phantom legend entries (rheolin.plots.layout).

    OPENBLAS_NUM_THREADS=1 python docs/gallery/make.py          # every figure (6 CPU minutes)
    OPENBLAS_NUM_THREADS=1 python docs/gallery/make.py study    # one figure, gallery.md anew

Exits 1 (and names the figure) when a figure has a problem.
"""

from __future__ import annotations

import functools
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from rheolin.data import example_path
from rheolin.io import load_model
from rheolin.plots import point as P
from rheolin.plots import stability as stability_plot
from rheolin.plots._common import save
from rheolin.plots.campbell import campbell_figure, critical_map_figure
from rheolin.plots.drawing import model_figure
from rheolin.plots.frf import bode_figure
from rheolin.plots.layout import problems
from rheolin.plots.modes import mode_shapes_figure
from rheolin.plots.study import parameter_figure
from rheolin.plots.sweep import sweep_figure
from rheolin.results import point_dataset, solve_point
from rheolin.results.frf import frequency_response
from rheolin.results.sweep import sweep_speeds
from rheolin.stability import campbell, stability_map
from rheolin.stability.critical_map import critical_speed_map

HERE = Path(__file__).parent
RPM = np.pi / 30
failures: list[str] = []


def figure(name: str, what: str, command: str, build: Callable[[], Any]) -> None:
    """Build one figure, check it, save it as docs/gallery/<name>.png."""
    t0 = time.perf_counter()
    fig = build()
    found = problems(fig)
    if found:
        failures.append(f"{name}: {'; '.join(found)}")
    save(fig, HERE / f"{name}.png")
    print(f"{name}: {time.perf_counter() - t0:.1f} s {'OK' if not found else found}", flush=True)


def stability_figure(smap: Any) -> Any:
    """The stability map's Figure (plot_stability only writes files)."""
    captured: list[Any] = []
    real = stability_plot.save
    stability_plot.save = lambda fig, path: captured.append(fig)  # type: ignore[assignment]
    try:
        stability_plot.plot_stability(smap, "unused.png")
    finally:
        stability_plot.save = real  # type: ignore[assignment]
    return captured[0]


@functools.cache
def model(name: str) -> Any:
    return load_model(example_path(name))


@functools.cache
def gearbox_point() -> Any:
    return point_dataset(solve_point(model("gearbox"), 3000 * RPM))


@functools.cache
def pair_point() -> Any:
    return point_dataset(solve_point(model("preloaded"), 1000 * RPM))


def study() -> Any:
    from rheolin.study import StudySpec, run_study

    spec = StudySpec.create(
        example_path("rotor"),
        np.arange(3000, 5501, 125) * RPM,
        {"bearings.drive_end.stiffness[0]": "2e7:8e7:4 N/m"},
    )
    return parameter_figure(run_study(spec, workers=1), "bearings.drive_end.stiffness[0]")


RUN = "rheolin run gearbox.toml --speed 3000rpm --out out"
PAIR = "rheolin run preloaded.toml --out pair"
FIGURES: list[tuple[str, str, str, Callable[[], Any]]] = [
    *[
        (
            f"drawing_{n}",
            f"model drawing of the {n} example, node numbers on",
            f"rheolin draw {n}.toml --nodes",
            functools.partial(lambda n: model_figure(model(n), nodes=True, title=n), n),
        )
        for n in ("gearbox", "rotor", "preloaded")
    ],
    (
        "run_orbits",
        "orbits about the static position (out/orbits.png)",
        RUN,
        lambda: P.orbits_figure(gearbox_point()),
    ),
    (
        "run_spectrum",
        "response spectrum, log-log, 60 dB (out/spectrum.png)",
        RUN,
        lambda: P.spectrum_figure(gearbox_point()),
    ),
    (
        "run_bearing_forces",
        "bearing load spectra (out/bearing_forces.png)",
        RUN,
        lambda: P.bearing_spectra_figure(gearbox_point()),
    ),
    (
        "run_convergence",
        "solver convergence and the backward error (out/convergence.png)",
        RUN,
        lambda: P.convergence_figure(gearbox_point()),
    ),
    (
        "preloaded_orbits",
        "a nanometre orbit under a 19 µm static sag",
        PAIR,
        lambda: P.orbits_figure(pair_point()),
    ),
    (
        "preloaded_bearing_forces",
        "an axial-only joint shows its axial force",
        PAIR,
        lambda: P.bearing_spectra_figure(pair_point()),
    ),
    (
        "sweep",
        "run-up: response per body and waterfall (sweep.png)",
        "rheolin sweep gearbox.toml --speeds 1500:4500:250rpm --out sweep",
        lambda: sweep_figure(
            sweep_speeds(model("gearbox"), np.arange(1500, 4501, 250) * RPM, stability=False)
        ),
    ),
    (
        "stability_map",
        "Floquet stability map: the rotor's asymmetric-shaft band",
        "rheolin sweep rotor.toml --speeds 1000:9000:250rpm --out rsweep",
        lambda: stability_figure(stability_map(model("rotor"), np.arange(1000, 9001, 250) * RPM)),
    ),
    (
        "campbell",
        "Campbell diagram coloured by whirl ratio, critical speeds circled",
        "rheolin campbell gearbox.toml --speeds 0:6000:500rpm --out campbell",
        lambda: campbell_figure(campbell(model("gearbox"), np.arange(0, 6001, 500) * RPM)),
    ),
    (
        "modes",
        "12 modes of the gearbox at 3000 rpm (modes.png)",
        "rheolin modes gearbox.toml --speed 3000rpm --out modes",
        lambda: mode_shapes_figure(model("gearbox"), 3000 * RPM, n_modes=12),
    ),
    (
        "bode",
        "receptance with its peak, AF and sidebands (bode.png)",
        "rheolin frf rotor.toml --speed 3000rpm --frequencies 1:150:0.25Hz "
        "--input rotor:1:ux --out frf",
        lambda: bode_figure(
            frequency_response(
                model("rotor"),
                3000 * RPM,
                np.arange(1.0, 150.0, 0.25) * 2 * np.pi,
                inputs=["rotor:1:ux"],
            )
        ),
    ),
    (
        "critical_map",
        "undamped critical-speed map (critical_map.png)",
        "rheolin critical-map rotor.toml --stiffness 1e6:1e9:13 --out cmap",
        lambda: critical_map_figure(critical_speed_map(model("rotor"), np.logspace(6, 9, 13))),
    ),
    (
        "study",
        "parameter study: response and unstable ranges against a bearing stiffness",
        "rheolin sweep rotor.toml --speeds 3000:5500:125rpm "
        "--vary 'bearings.drive_end.stiffness[0]=2e7:8e7:4 N/m' --out study",
        study,
    ),
]


def main(only: list[str]) -> int:
    """Draw the figures (those named in ``only``, or all), then write docs/gallery.md."""
    unknown = set(only) - {name for name, *_ in FIGURES}
    if unknown:
        print(f"no figure named {sorted(unknown)}", file=sys.stderr)
        return 2
    for name, what, command, build in FIGURES:
        if not only or name in only:
            figure(name, what, command, build)
    lines = [
        "# Gallery: every figure rheolin draws",
        "",
        "Made by `OPENBLAS_NUM_THREADS=1 python docs/gallery/make.py` (or `... make.py NAME` for",
        "one figure) from the embedded examples (`rheolin example NAME > NAME.toml`); each figure",
        "is checked for overlapping labels, empty panels and legend entries without their artist",
        "(`rheolin.plots.layout`) and the script fails on any. The HTML report of a result",
        "directory (`rheolin report DIR`) shows the same results as interactive figures.",
        "",
    ]
    for name, what, command, _ in FIGURES:
        lines += [f"## {what}", "", f"`{command}`", "", f"![{name}](gallery/{name}.png)", ""]
    (HERE.parent / "gallery.md").write_text("\n".join(lines), encoding="utf-8")
    for f in failures:
        print("problem:", f, file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
