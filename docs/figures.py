"""Draw the figures of the README and docs/ from the embedded examples.

    python docs/figures.py            # writes docs/images/gearbox_campbell.png

The Campbell diagram of the embedded two-stage gearbox (``rheolin example gearbox``) from
standstill to 6000 rpm in steps of 100 rpm, with the Floquet stability map of the full
time-periodic system over the same speeds: the data of
``rheolin campbell gearbox.toml --speeds 0:6000:100rpm``, drawn on one panel for the README.
It takes a few minutes, most of them the stability map.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

os.environ.setdefault("MPLBACKEND", "Agg")

from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from rheolin.data import example_path
from rheolin.io import load_model
from rheolin.stability import CampbellResult, StabilityMap, campbell, stability_map

IMAGES = Path(__file__).resolve().parent / "images"
RPM = 30.0 / np.pi  # rpm per rad/s
HZ = 1.0 / (2.0 * np.pi)  # Hz per rad/s
KINDS = {"lateral": "tab:blue", "torsional": "tab:green", "axial": "tab:orange"}
COUPLED = "tab:purple"


def gearbox_data(step_rpm: float = 100.0) -> tuple[CampbellResult, StabilityMap]:
    """Campbell diagram and stability map of the embedded gearbox, 0-6000 rpm."""
    model = load_model(example_path("gearbox"))
    speeds = np.arange(0.0, 6000.0 + step_rpm / 2, step_rpm) / RPM
    return campbell(model, speeds), stability_map(model, speeds[speeds > 0])


def kind_colour(kind: str) -> str:
    """The colour of a branch by its kind at one speed (lateral, torsional, axial, coupled).

    >>> kind_colour("lateral forward"), kind_colour("coupled (lateral+torsional)")
    ('tab:blue', 'tab:purple')
    """
    return KINDS.get(kind.split(" ")[0], COUPLED)


def verdicts(smap: StabilityMap) -> str:
    """The Floquet verdicts in one line: decided stable, undecided (which speeds), unstable."""
    decided = np.asarray(smap.decided, dtype=bool)
    stable = np.asarray(smap.stable, dtype=bool) & decided
    text = f"Floquet: stable at {stable.sum()} of {stable.size} speeds"
    if (~decided).any():
        rpm = ", ".join(f"{w * RPM:.0f}" for w in smap.speeds[~decided][:4])
        text += f", undecided at {rpm} rpm"
    if smap.ranges:
        text += f", {len(smap.ranges)} unstable range(s)"
    return text + f"; largest real part {float(np.nanmax(smap.max_real)):.1f} 1/s"


def draw(result: CampbellResult, smap: StabilityMap, path: Path, fmax_hz: float = 2500.0) -> Path:
    """One panel: the branches coloured by kind, the order lines, the critical speeds and
    the Floquet verdict in the title."""
    fig = Figure(figsize=(8.0, 5.2), layout="constrained")
    ax: Any = fig.subplots()
    rpm = result.speeds * RPM
    freq = result.frequency * HZ
    kinds = np.asarray(result.kind, dtype=object)
    for j in range(freq.shape[1]):
        for i in range(freq.shape[0] - 1):  # segment by segment: a branch may change kind
            if np.isfinite(freq[i : i + 2, j]).all() and freq[i, j] <= fmax_hz:
                colour = kind_colour(str(kinds[i, j]))
                ax.plot(rpm[i : i + 2], freq[i : i + 2, j], "-", lw=1.4, color=colour)
    top = rpm[-1]
    for name, ratio in result.orders.items():
        mesh = name.startswith("mesh")
        line = ratio * result.speeds * HZ
        style = {"color": "tab:red", "lw": 1.1} if mesh else {"color": "0.55", "lw": 0.7}
        ax.plot(rpm, line, "--", **style)
        if mesh:
            end = min(top, fmax_hz / (ratio * HZ) * RPM)
            ax.annotate(
                name,
                (end, min(fmax_hz, ratio * end / RPM * HZ)),
                xytext=(-4, 4),
                textcoords="offset points",
                ha="right",
                fontsize=8,
                color="tab:red",
            )
    for c in result.critical_speeds:
        if c.frequency * HZ <= fmax_hz:
            ax.plot(c.speed * RPM, c.frequency * HZ, "o", ms=8, mfc="none", mec="k", mew=1.0)
    ax.set_title(
        f"Two-stage gearbox 23:67 / 19:71, Campbell diagram\n{verdicts(smap)}", fontsize=10
    )
    ax.set_xlim(rpm[0], top)
    ax.set_ylim(0.0, fmax_hz)
    ax.set_xlabel("input speed [rpm]")
    ax.set_ylabel("damped natural frequency [Hz]")
    ax.grid(alpha=0.3)
    handles = [Line2D([], [], color=c, lw=1.4, label=k) for k, c in KINDS.items()]
    handles += [
        Line2D([], [], color=COUPLED, lw=1.4, label="coupled"),
        Line2D([], [], color="tab:red", ls="--", lw=1.1, label="mesh orders"),
        Line2D([], [], color="0.55", ls="--", lw=0.7, label="shaft orders 1x, 2x"),
        Line2D([], [], color="k", marker="o", mfc="none", ls="none", label="critical speed"),
    ]
    ax.legend(handles=handles, fontsize=8, loc="upper left", ncol=2, framealpha=0.9)
    fig.savefig(path, dpi=110)
    return path


if __name__ == "__main__":
    IMAGES.mkdir(exist_ok=True)
    print(draw(*gearbox_data(), IMAGES / "gearbox_campbell.png"))
