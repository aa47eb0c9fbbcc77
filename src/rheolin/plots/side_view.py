"""The side view of a shaft line for the model drawing (:mod:`rheolin.plots.drawing`): shaft
sections to scale, disks and gears, supports by kind, meshes, links, condensed bodies,
torques, node numbers; and the frame and sizes the end view shares.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.patches import Circle, Polygon, Rectangle

from .geometry import Geometry

__all__ = [
    "BOX",
    "COLOURS",
    "MM",
    "axis_name",
    "frame",
    "radius_at",
    "side_view",
    "support_size",
    "support_symbol",
]

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


def frame(geo: Geometry, bodies: list[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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


def axis_name(v: np.ndarray) -> str:
    k = int(np.argmax(np.abs(v)))
    if abs(abs(v[k]) - 1.0) < 1e-9:
        return ("-" if v[k] < 0 else "") + "xyz"[k]
    return "(" + ", ".join(f"{x:.2g}" for x in v) + ")"


def radius_at(geo: Geometry, body: str, node: int) -> float:
    r = [
        max(s.outer) / 2
        for s in geo.segments
        if s.body == body and node in (s.element, s.element + 1)
    ]
    return max(r) if r else 0.0


def side_view(ax: Any, geo: Geometry, bodies: list[str], nodes: bool) -> tuple[set[str], list]:
    """One shaft line seen from the side; returns the kinds of item drawn (for the legend)
    and the labels, the most important first."""
    e, d, _ = frame(geo, bodies)
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
                r = radius_at(geo, b, k) * MM
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
        drawn.add(support_symbol(ax, geo, support, hv, labels))
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
        left -= 0.5 * support_size(geo, b, 0)
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
    ax.set_xlabel(f"along the axis {axis_name(e)} [mm]")
    ax.set_ylabel(f"{axis_name(d)} [mm]")
    ax.grid(alpha=0.2)
    return drawn, labels + numbers


def support_size(geo: Geometry, body: str, node: int) -> float:
    """The drawn size of a support symbol [mm]."""
    r = radius_at(geo, body, node) * MM or 0.01 * geo.extent() * MM
    return max(0.6 * r, 0.012 * geo.extent() * MM)


def support_symbol(ax: Any, geo: Geometry, s: Any, hv: Any, labels: list) -> str:
    """A support: blocks above and below the shaft (radial), a darker block with an arrow
    (axial), a spiral mark (torsional), a spring line to the other body's node."""
    h, v = hv(s.point)
    r = radius_at(geo, s.body, s.node) * MM or 0.01 * geo.extent() * MM
    size = support_size(geo, s.body, s.node)
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
