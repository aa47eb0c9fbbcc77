"""The drawing of a model: a side view of every shaft line (shaft sections, disks, gears,
bearings, couplings, links, condensed bodies, node numbers on demand) and an end view of the
gear train (pitch circles, meshes, tooth counts, speed ratios).

``rheolin draw model.toml`` writes it; the HTML report embeds it.

>>> import numpy as np, tempfile, pathlib, rheolin as rl
>>> m = rl.Model()
>>> m.add_shaft("s", np.linspace(0, 0.5, 6), outer_diameter=0.04, material="steel")
>>> m.add_disk("s", 2, outer_diameter=0.25, width=0.04, material="steel", unbalance=1e-4)
>>> for k in (0, 5):
...     m.add_bearing(f"b{k}", "s", k, stiffness=1e8)
>>> fig = model_figure(m, nodes=True)
>>> from rheolin.plots.layout import problems
>>> problems(fig)
[]
>>> draw_model(m, pathlib.Path(tempfile.mkdtemp()) / "m.png").stat().st_size > 10000
True
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch

from ._common import save
from .geometry import Geometry, model_geometry
from .layout import drop_overlapping
from .side_view import COLOURS, MM, axis_name, frame, radius_at, side_view

__all__ = ["draw_model", "model_figure"]


def _end_view(ax: Any, geo: Geometry, bodies: list[str]) -> list:
    """The gear train seen along the axis: shafts, pitch circles, meshes, ratios; returns
    the labels, the most important first."""
    e, d, d2 = frame(geo, bodies)

    def xy(p: np.ndarray) -> tuple[float, float]:
        return float(p @ d2) * MM, float(p @ d) * MM

    labels = []
    for disk in geo.disks:
        if disk.body not in bodies:
            continue
        x, y = xy(disk.centre)
        gear = disk.mesh is not None
        r = (disk.pitch if gear and disk.pitch else disk.outer) / 2 * MM
        ax.add_patch(
            Circle(
                (x, y),
                r,
                fc=COLOURS["gear" if gear else "disk"],
                alpha=0.25,
                ec=COLOURS["gear" if gear else "disk"],
                lw=1.2,
            )
        )
        if gear:
            labels.append(
                ax.annotate(
                    f"z {disk.teeth}",
                    (x, y + r),
                    xytext=(0, -3),
                    textcoords="offset points",
                    ha="center",
                    va="top",
                    fontsize=7,
                )
            )
    for b in bodies:
        x, y = xy(geo.nodes[b][0])
        r = max([radius_at(geo, b, k) for k in range(len(geo.nodes[b]))] + [0.0]) * MM
        ax.add_patch(Circle((x, y), max(r, 1.0), fc=COLOURS["shaft"], ec="0.2", lw=0.8, zorder=4))
        ratio = geo.speed_ratios.get(b)
        turn = (
            ""
            if ratio is None
            else f"\n{abs(ratio):.4g} x input" + (" (reversed)" if ratio < 0 else "")
        )
        if ratio == 0:
            turn = "\nnot rotating"
        labels.insert(
            0,
            ax.annotate(
                b + turn,
                (x, y),
                xytext=(0, -r - 4 if r else -6),
                textcoords="offset points",
                ha="center",
                va="top",
                fontsize=7,
                weight="bold",
                zorder=8,
            ),
        )
    for m in geo.meshes:
        (xp, yp), (xg, yg) = xy(m.pinion_centre), xy(m.gear_centre)
        ax.plot([xp, xg], [yp, yg], ":", color=COLOURS["mesh"], lw=0.9)
        n = np.hypot(xg - xp, yg - yp) or 1.0
        sign = -1.0 if m.internal else 1.0
        cx = xp + sign * (xg - xp) / n * m.pinion_pitch / 2 * MM
        cy = yp + sign * (yg - yp) / n * m.pinion_pitch / 2 * MM
        ax.plot(cx, cy, "X", color=COLOURS["mesh"], ms=8, mec="white", mew=0.8, zorder=6)
        labels.append(
            ax.annotate(
                m.name,
                (cx, cy),
                xytext=(0, 6),
                textcoords="offset points",
                ha="center",
                fontsize=7,
                color=COLOURS["mesh"],
                zorder=7,
            )
        )
    ax.set_aspect("equal", adjustable="datalim")
    ax.autoscale_view()
    ax.margins(0.1)
    ax.set_xlabel(f"{axis_name(d2)} [mm]")
    ax.set_ylabel(f"{axis_name(d)} [mm]")
    ax.set_title(f"gear train, seen along {axis_name(e)}", fontsize=10)
    ax.grid(alpha=0.2)
    return labels


_LEGEND = {
    "shaft": Patch(fc=COLOURS["shaft"], ec="0.25", label="shaft (Timoshenko elements)"),
    "section": Patch(
        fc=COLOURS["shaft"],
        ec="0.25",
        hatch="//",
        label="non-circular section (circle of its area)",
    ),
    "disk": Patch(fc=COLOURS["disk"], ec="0.15", label="disk"),
    "gear": Patch(fc=COLOURS["gear"], ec="0.15", hatch="||", label="gear (dashed: pitch diameter)"),
    "radial": Patch(fc=COLOURS["radial"], ec="k", label="bearing (radial)"),
    "axial": Patch(fc=COLOURS["axial"], ec="k", label="bearing (radial + axial)"),
    "rolling": Line2D(
        [],
        [],
        marker="o",
        ls="",
        mfc="white",
        mec="k",
        ms=6,
        label="rolling bearing (load-dependent)",
    ),
    "torsional": Line2D([], [], color=COLOURS["torsional"], label="torsional coupling / spring"),
    "thrust": Line2D(
        [],
        [],
        marker="$\\leftrightarrow$",
        ls="",
        ms=10,
        color=COLOURS["axial"],
        label="axial support",
    ),
    "between": Line2D([], [], color=COLOURS["between"], label="bearing between bodies"),
    "mesh": Line2D([], [], marker="X", ls="", color=COLOURS["mesh"], label="gear mesh contact"),
    "link": Line2D([], [], ls="--", color=COLOURS["link"], label="rigid link"),
    "condensed": Line2D([], [], ls="--", color=COLOURS["condensed"], label="condensed body"),
}


def _make_room(ax: Any, texts: list[Any]) -> None:
    """Widen the view so that ``texts`` (the shaft names left of each line) lie inside it."""
    fig = ax.get_figure(root=True)
    renderer = fig.canvas.get_renderer() if hasattr(fig.canvas, "get_renderer") else None
    if renderer is None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw_without_rendering()
    for t in texts:
        x0, y0 = ax.transData.inverted().transform(t.get_window_extent(renderer).p0)
        ax.update_datalim([(x0, y0)])
    ax.autoscale_view()


def _aspect(geo: Geometry, bodies: list[str], end: bool) -> float:
    """Width over height of a line's drawing (side view, or end view with ``end``)."""
    e, d, d2 = frame(geo, bodies)
    pts = np.concatenate([geo.nodes[b] for b in bodies])
    radius = max([x.outer / 2 for x in geo.disks if x.body in bodies] + [0.02 * geo.extent()])
    across = float(np.ptp(pts @ d)) + 2 * radius
    along = float(np.ptp(pts @ (d2 if end else e))) + 2 * (radius if end else 0.1 * across)
    return float(np.clip(along / max(across, 1e-9), 0.6, 3.0))


def model_figure(model: Any, *, nodes: bool = False, title: str | None = None) -> Figure:
    """The drawing of ``model`` (see the module docstring) as a Figure: one side view per
    shaft line (bodies with parallel axes), and the gear train seen along the axis when the
    model has gear meshes. ``nodes``: write each node's index under it."""
    geo = model_geometry(model)
    lines = geo.lines()
    end = bool(geo.meshes)
    height = 5.4
    side = [_aspect(geo, b, False) for b in lines]
    widths = [max(side) * height] + ([_aspect(geo, lines[0], True) * height] if end else [])
    size = (min(max(sum(widths) + 1.5, 8.0), 15.0), height * len(lines) + 1.6)
    fig = Figure(figsize=size, layout="constrained")
    grid = fig.add_gridspec(len(lines), len(widths), width_ratios=widths)
    drawn: set[str] = set()
    all_labels: list[Any] = []
    for i, bodies in enumerate(lines):
        ax = fig.add_subplot(grid[i, 0])
        kinds, labels = side_view(ax, geo, bodies, nodes)
        drawn |= kinds
        all_labels += labels
        _make_room(ax, labels[: len(bodies)])
        ax.set_title(
            f"side view: {', '.join(bodies)}" if len(lines) > 1 else "side view", fontsize=10
        )
        if end and i == 0:
            all_labels += _end_view(fig.add_subplot(grid[0, 1]), geo, bodies)
    handles = [_LEGEND[k] for k in _LEGEND if k in drawn]
    if any(d.unbalance for d in geo.disks):
        handles.append(Line2D([], [], marker="v", ls="", color="tab:red", label="unbalance"))
    if handles:
        fig.legend(
            handles=handles, loc="outside lower center", ncol=min(4, len(handles)), fontsize=8
        )
    fig.suptitle(title or "model drawing", fontsize=11)
    keep = [fig.legends[0]] if fig.legends else []
    drop_overlapping(all_labels, keep=keep)
    return fig


def draw_model(
    model: Any, path: str | Path, *, nodes: bool = False, title: str | None = None
) -> Path:
    """Write the drawing of ``model`` (:func:`model_figure`) as PNG, or SVG/PDF by the
    file's suffix."""
    fig = model_figure(model, nodes=nodes, title=title)
    return save(fig, path)
