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
from matplotlib.patches import Circle, Patch, Polygon, Rectangle

from ._common import save
from .geometry import Geometry, model_geometry
from .layout import drop_overlapping

__all__ = ["draw_model", "model_figure"]

MM = 1e3
#: Labels drawn over shapes stay legible on a light box.
BOX = {"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.75}
COLOURS = {
    "shaft": "#9aa5b1",
    "layer": "#cfd6dd",
    "disk": "#6b7b8c",
    "gear": "#e69f00",
    "radial": "#1f77b4",
    "axial": "#08306b",
    "torsional": "#7b3294",
    "between": "#2ca02c",
    "mesh": "#d62728",
    "link": "#000000",
    "condensed": "#8c564b",
}


def _frame(geo: Geometry, bodies: list[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(e, d, d2)``: the line's axis, the transverse direction of its bodies' largest
    spread (drawn upwards in the side view) and ``e x d``."""
    e = geo.axes[bodies[0]]
    pts = np.concatenate([geo.nodes[b] for b in bodies])
    flat = pts - np.outer(pts @ e, e)
    flat = flat - flat.mean(axis=0)
    _, s, vt = np.linalg.svd(flat, full_matrices=False)
    if s.size and s[0] > 1e-9:
        d = vt[0]
    else:  # one line: the global axis most perpendicular to it
        d = np.eye(3)[int(np.argmin(np.abs(e)))]
    d = d - (d @ e) * e
    d /= np.linalg.norm(d)
    if d[int(np.argmax(np.abs(d)))] < 0:  # the positive global direction upwards
        d = -d
    return e, d, np.cross(e, d)


def _axis_name(v: np.ndarray) -> str:
    k = int(np.argmax(np.abs(v)))
    if abs(abs(v[k]) - 1.0) < 1e-9:
        return ("-" if v[k] < 0 else "") + "xyz"[k]
    return "(" + ", ".join(f"{x:.2g}" for x in v) + ")"


def _radius_at(geo: Geometry, body: str, node: int) -> float:
    r = [
        max(s.outer) / 2
        for s in geo.segments
        if s.body == body and node in (s.element, s.element + 1)
    ]
    return max(r) if r else 0.0


def _side_view(ax: Any, geo: Geometry, bodies: list[str], nodes: bool) -> tuple[set[str], list]:
    """One shaft line seen from the side; returns the kinds of item drawn (for the legend)
    and the labels, the most important first."""
    e, d, _ = _frame(geo, bodies)
    extent = geo.extent()

    def hv(p: np.ndarray) -> tuple[float, float]:
        return float(p @ e) * MM, float(p @ d) * MM

    drawn: set[str] = set()
    labels: list[Any] = []
    numbers: list[Any] = []  # node numbers: the first to give way
    inside = set(bodies)
    for layer in (1, 0):
        for s in geo.segments:
            if s.body not in inside or (s.layer > 0) != (layer == 1):
                continue
            (h0, v0), (h1, v1) = hv(s.start), hv(s.end)
            r0, r1 = s.outer[0] / 2 * MM, s.outer[1] / 2 * MM
            colour = COLOURS["layer" if s.layer else "shaft"]
            ax.add_patch(
                Polygon(
                    [(h0, v0 - r0), (h1, v1 - r1), (h1, v1 + r1), (h0, v0 + r0)],
                    closed=True,
                    fc=colour,
                    ec="0.25",
                    lw=0.6,
                    hatch="//" if s.section else None,
                )
            )
            i0, i1 = s.inner[0] / 2 * MM, s.inner[1] / 2 * MM
            if max(i0, i1) > 0:
                ax.add_patch(
                    Polygon(
                        [(h0, v0 - i0), (h1, v1 - i1), (h1, v1 + i1), (h0, v0 + i0)],
                        closed=True,
                        fc="white",
                        ec="0.5",
                        lw=0.4,
                    )
                )
            drawn.add("section" if s.section else "shaft")
    for b in bodies:
        pts = np.array([hv(p) for p in geo.nodes[b]])
        ax.plot(pts[:, 0], pts[:, 1], "-.", color="0.35", lw=0.6)
        ax.plot(pts[:, 0], pts[:, 1], "|", color="0.2", ms=5)
        if nodes:
            for k, (h, v) in enumerate(pts):
                r = _radius_at(geo, b, k) * MM
                numbers.append(
                    ax.annotate(
                        str(k),
                        (h, v),
                        xytext=(0, -2),
                        textcoords="offset points",
                        ha="center",
                        va="top",
                        fontsize=6,
                        color="0.15",
                        bbox=BOX,
                        zorder=10,
                    )
                )
        kind = geo.kinds[b]
        if kind == "condensed":
            pad = 0.02 * extent * MM
            lo, hi = pts.min(axis=0) - pad, pts.max(axis=0) + pad
            ax.add_patch(
                Rectangle(
                    tuple(lo), *(hi - lo), fc="none", ec=COLOURS["condensed"], ls="--", lw=1.0
                )
            )
            ax.plot(pts[:, 0], pts[:, 1], "s", color=COLOURS["condensed"], ms=4)
            modes = geo.condensed_modes.get(b, 0)
            ax.annotate(
                f"{b} (condensed, {modes} modes)",
                (lo[0], hi[1]),
                fontsize=7,
                color=COLOURS["condensed"],
                va="bottom",
            )
            drawn.add("condensed")
    for disk in geo.disks:
        if disk.body not in inside:
            continue
        h, v = hv(disk.centre)
        w, r = disk.width * MM, disk.outer / 2 * MM
        gear = disk.mesh is not None
        ax.add_patch(
            Rectangle(
                (h - w / 2, v - r),
                w,
                2 * r,
                fc=COLOURS["gear" if gear else "disk"],
                ec="0.15",
                lw=0.7,
                alpha=0.9,
                hatch="||" if gear else None,
                zorder=3,
            )
        )
        if gear and disk.pitch:
            p = disk.pitch / 2 * MM
            ax.plot([h - w / 2, h + w / 2], [v - p, v - p], "--", color="k", lw=0.6, zorder=4)
            ax.plot([h - w / 2, h + w / 2], [v + p, v + p], "--", color="k", lw=0.6, zorder=4)
        if disk.unbalance:
            ax.plot(h, v + r, "v", color="tab:red", ms=4, zorder=5)
        drawn.add("gear" if gear else "disk")
    for support in geo.supports:
        if support.body not in inside:
            continue
        drawn.add(_support_symbol(ax, geo, support, hv, labels))
    for m in geo.meshes:
        if m.pinion[0] not in inside or m.gear[0] not in inside:
            continue
        (hp, vp), (hg, vg) = hv(m.pinion_centre), hv(m.gear_centre)
        sign = 1.0 if vg >= vp else -1.0
        contact = ((hp + hg) / 2, vp + sign * m.pinion_pitch / 2 * MM)
        ax.plot(*contact, "X", color=COLOURS["mesh"], ms=8, mec="white", mew=0.8, zorder=6)
        labels.append(
            ax.annotate(
                f"{m.name} {m.pinion_teeth}:{m.gear_teeth}",
                contact,
                xytext=(7, 0),
                textcoords="offset points",
                fontsize=7,
                color=COLOURS["mesh"],
                va="center",
                zorder=10,
                bbox=BOX,
            )
        )
        drawn.add("mesh")
    for link in geo.links:
        (h0, v0), (h1, v1) = hv(link.start), hv(link.end)
        ax.plot([h0, h1], [v0, v1], "--", color=COLOURS["link"], lw=1.2)
        drawn.add("link")
    for b in bodies:
        pts = np.array([hv(p) for p in geo.nodes[b]])
        left = min(
            [pts[0, 0]] + [hv(d.centre)[0] - d.width / 2 * MM for d in geo.disks if d.body == b]
        )
        left -= 0.5 * _support_size(geo, b, 0)
        labels.insert(
            0,
            ax.annotate(
                b,
                (left, pts[0, 1]),
                xytext=(-5, 0),
                textcoords="offset points",
                ha="right",
                va="center",
                fontsize=8,
                weight="bold",
                zorder=10,
                bbox=BOX,
            ),
        )
    for name, (b, k, torque) in geo.torques.items():
        if b not in inside:
            continue
        h, v = hv(geo.nodes[b][k])
        text = (
            f"{name}: {torque:.4g} N m" if isinstance(torque, int | float) else f"{name}: {torque}"
        )
        labels.append(
            ax.annotate(
                "\u21bb " + text,
                (h, v),
                xytext=(0, 10),
                textcoords="offset points",
                ha="center",
                fontsize=7,
                color="tab:brown",
                zorder=10,
                bbox=BOX,
            )
        )
    ax.set_aspect("equal", adjustable="datalim")
    ax.autoscale_view()
    ax.margins(0.08)
    ax.set_xlabel(f"along the axis {_axis_name(e)} [mm]")
    ax.set_ylabel(f"{_axis_name(d)} [mm]")
    ax.grid(alpha=0.2)
    return drawn, labels + numbers


def _support_size(geo: Geometry, body: str, node: int) -> float:
    """The drawn size of a support symbol [mm]."""
    r = _radius_at(geo, body, node) * MM or 0.01 * geo.extent() * MM
    return max(0.6 * r, 0.012 * geo.extent() * MM)


def _support_symbol(ax: Any, geo: Geometry, s: Any, hv: Any, labels: list) -> str:
    """A support: blocks above and below the shaft (radial), a darker block with an arrow
    (axial), a spiral mark (torsional), a spring line to the other body's node."""
    h, v = hv(s.point)
    r = _radius_at(geo, s.body, s.node) * MM or 0.01 * geo.extent() * MM
    size = _support_size(geo, s.body, s.node)
    if s.other is not None and s.other_point is not None:
        h2, v2 = hv(s.other_point)
        t = np.linspace(0, 1, 41)
        zig = 0.25 * size * np.sign(np.sin(t * 8 * np.pi)) * (t > 0.15) * (t < 0.85)
        dx, dy = h2 - h, v2 - v
        n = np.hypot(dx, dy) or 1.0
        ax.plot(
            h + t * dx - zig * dy / n, v + t * dy + zig * dx / n, color=COLOURS["between"], lw=0.9
        )
        labels.append(
            ax.annotate(
                s.name,
                ((h + h2) / 2, (v + v2) / 2),
                xytext=(4, 0),
                textcoords="offset points",
                fontsize=6,
                color=COLOURS["between"],
            )
        )
        return "between"
    kind = s.kind
    if "radial" in kind:
        colour = COLOURS["axial" if "axial" in kind else "radial"]
        for sign in (-1, 1):
            y0 = v + sign * r + (0 if sign > 0 else -size)
            ax.add_patch(
                Rectangle((h - size / 2, y0), size, size, fc=colour, ec="k", lw=0.5, zorder=5)
            )
            if s.rolling:
                ax.add_patch(
                    Circle((h, y0 + size / 2), 0.3 * size, fc="white", ec="k", lw=0.4, zorder=6)
                )
        ground = v - r - size
        ax.plot([h - size, h + size], [ground, ground], color="k", lw=1.0)
        for x in np.linspace(h - size, h + size, 4):
            ax.plot([x, x - 0.4 * size], [ground, ground - 0.4 * size], color="k", lw=0.5)
        labels.append(
            ax.annotate(
                s.name,
                (h, ground - 0.4 * size),
                xytext=(0, -2),
                textcoords="offset points",
                ha="center",
                va="top",
                fontsize=6,
                color=colour,
            )
        )
        if "axial" in kind:
            ax.annotate(
                "",
                (h + size, v + r + size / 2),
                (h - size, v + r + size / 2),
                arrowprops={"arrowstyle": "<->", "color": "white", "lw": 0.8},
                zorder=7,
            )
        return "rolling" if s.rolling else ("axial" if "axial" in kind else "radial")
    colour = COLOURS["torsional" if "torsional" in kind or "tilting" in kind else "axial"]
    if "torsional" in kind or "tilting" in kind:
        t = np.linspace(0, 4 * np.pi, 60)
        rr = 0.15 * size + 0.35 * size * t / t[-1]
        ax.plot(h + rr * np.cos(t), v + rr * np.sin(t), color=colour, lw=0.9, zorder=6)
    if "axial" in kind:  # a thrust: an arrow pair along the axis
        ax.annotate(
            "",
            (h + size, v),
            (h - size, v),
            zorder=6,
            arrowprops={"arrowstyle": "<->", "color": COLOURS["axial"], "lw": 1.2},
        )
    labels.append(
        ax.annotate(
            s.name,
            (h, v - 0.6 * size),
            xytext=(0, -2),
            textcoords="offset points",
            ha="center",
            va="top",
            fontsize=6,
            color=colour,
            zorder=10,
            bbox=BOX,
        )
    )
    return "torsional" if "torsional" in kind or "tilting" in kind else "thrust"


def _end_view(ax: Any, geo: Geometry, bodies: list[str]) -> list:
    """The gear train seen along the axis: shafts, pitch circles, meshes, ratios; returns
    the labels, the most important first."""
    e, d, d2 = _frame(geo, bodies)

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
        r = max([_radius_at(geo, b, k) for k in range(len(geo.nodes[b]))] + [0.0]) * MM
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
    ax.set_xlabel(f"{_axis_name(d2)} [mm]")
    ax.set_ylabel(f"{_axis_name(d)} [mm]")
    ax.set_title(f"gear train, seen along {_axis_name(e)}", fontsize=10)
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
    e, d, d2 = _frame(geo, bodies)
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
        kinds, labels = _side_view(ax, geo, bodies, nodes)
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
