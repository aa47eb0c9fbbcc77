"""The shapes of a model, for its drawing: shaft sections, disks and gears, supports,
meshes, links and condensed bodies, in global coordinates [m].

Read from the model's tables (:class:`~rheolin.mechanics.items.ModelData`) and, for the disk
dimensions that the tables keep only as mass properties, from the recorded ``add_disk`` calls
(a disk given by mass and inertia gets the uniform disk of the same mass and inertia).

>>> import rheolin as rl
>>> m = rl.Model()
>>> m.add_shaft("s", [0.0, 0.1, 0.2], outer_diameter=0.04, material="steel")
>>> m.add_disk("s", 1, outer_diameter=0.2, width=0.03, material="steel")
>>> m.add_bearing("A", "s", 0, stiffness=1e8)
>>> g = model_geometry(m)
>>> [(s.body, s.element, s.outer) for s in g.segments]
[('s', 0, (0.04, 0.04)), ('s', 1, (0.04, 0.04))]
>>> g.disks[0].outer, g.supports[0].kind
(0.2, 'radial')
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = [
    "DiskShape",
    "Geometry",
    "LinkShape",
    "MeshShape",
    "Segment",
    "Support",
    "model_geometry",
    "section_diameters",
    "support_kind",
]


@dataclass(frozen=True)
class Segment:
    """One shaft element (or a layer on it): axial ends ``s`` along its body's axis [m],
    outer and inner diameters at both ends [m]; ``section``: a non-circular section drawn as
    the circle of the same area."""

    body: str
    element: int
    start: np.ndarray
    end: np.ndarray
    outer: tuple[float, float]
    inner: tuple[float, float]
    layer: int = 0
    section: bool = False


@dataclass(frozen=True)
class DiskShape:
    """A disk or gear blank: centre [m], diameters and width [m]; a gear names its mesh and
    has its tooth count and pitch diameter."""

    body: str
    node: int
    centre: np.ndarray
    outer: float
    inner: float
    width: float
    mesh: str | None = None
    teeth: int | None = None
    pitch: float | None = None
    unbalance: bool = False


@dataclass(frozen=True)
class Support:
    """A bearing, seal or coupling (``rolling``: the law of a load-dependent bearing), at
    ``point`` [m], to ground or to ``other`` (body, node) at ``other_point``."""

    name: str
    body: str
    node: int
    point: np.ndarray
    kind: str
    other: tuple[str, int] | None = None
    other_point: np.ndarray | None = None
    rolling: str | None = None


@dataclass(frozen=True)
class MeshShape:
    """A gear mesh: the two gears' centres [m], pitch diameters [m], tooth counts."""

    name: str
    pinion: tuple[str, int]
    gear: tuple[str, int]
    pinion_centre: np.ndarray
    gear_centre: np.ndarray
    pinion_teeth: int
    gear_teeth: int
    pinion_pitch: float
    gear_pitch: float
    internal: bool = False


@dataclass(frozen=True)
class LinkShape:
    """A rigid link between two nodes."""

    name: str
    start: np.ndarray
    end: np.ndarray


@dataclass
class Geometry:
    """Everything drawn of a model (see :func:`model_geometry`)."""

    axes: dict[str, np.ndarray]
    nodes: dict[str, np.ndarray]
    kinds: dict[str, str]
    speed_ratios: dict[str, float]
    segments: list[Segment] = field(default_factory=list)
    disks: list[DiskShape] = field(default_factory=list)
    supports: list[Support] = field(default_factory=list)
    meshes: list[MeshShape] = field(default_factory=list)
    links: list[LinkShape] = field(default_factory=list)
    condensed_modes: dict[str, int] = field(default_factory=dict)
    torques: dict[str, tuple[str, int, Any]] = field(default_factory=dict)

    def lines(self) -> list[list[str]]:
        """Bodies grouped by parallel axes (a shaft line each), the largest group first."""
        groups: list[list[str]] = []
        for name, e in self.axes.items():
            for g in groups:
                if abs(abs(float(np.dot(self.axes[g[0]], e))) - 1.0) < 1e-6:
                    g.append(name)
                    break
            else:
                groups.append([name])
        return sorted(groups, key=len, reverse=True)

    def extent(self) -> float:
        """The largest distance between two nodes, at least the largest diameter [m]."""
        pts = np.concatenate(list(self.nodes.values()))
        span = float(np.ptp(pts, axis=0).max()) if len(pts) > 1 else 0.0
        biggest = max([d.outer for d in self.disks] + [s.outer[0] for s in self.segments] + [0])
        return max(span, biggest, 1e-3)


def support_kind(components: Sequence[str] | None) -> str:
    """``"radial"``, ``"axial"``, ``"torsional"``, ``"tilting"`` or their combination
    (``"radial+axial"``) from the components a joint acts on (None: all six).

    >>> support_kind(["ux", "uy", "uz"]), support_kind(["phiz"]), support_kind(None)
    ('radial+axial', 'torsional', 'radial+axial+tilting+torsional')
    """
    comps = set(components or ("ux", "uy", "uz", "phix", "phiy", "phiz"))
    parts = []
    if comps & {"ux", "uy"}:
        parts.append("radial")
    if "uz" in comps:
        parts.append("axial")
    if comps & {"phix", "phiy"}:
        parts.append("tilting")
    if "phiz" in comps:
        parts.append("torsional")
    return "+".join(parts) or "none"


def _local(components: Sequence[str] | None, e: np.ndarray) -> Sequence[str] | None:
    """Joint components named in global axes, read in the body's axes (``uz`` = along the
    spin axis ``e``), so that a shaft along x has ``ux`` as its axial component."""
    if components is None:
        return None
    k = int(np.argmax(np.abs(e)))
    if abs(abs(e[k]) - 1.0) > 1e-9:
        return components  # a skew axis: the global names are the best guess
    along = "xyz"[k]
    rename = {f"u{along}": "uz", f"phi{along}": "phiz", "uz": f"u{along}", "phiz": f"phi{along}"}
    return [rename.get(c, c) for c in components]


def _disk_calls(model: Any) -> dict[tuple[str, int], dict[str, Any]]:
    """The geometry arguments of the last ``add_disk`` call that set each node's disk."""
    out: dict[tuple[str, int], dict[str, Any]] = {}
    for method, args in getattr(model, "calls", []):
        if method != "add_disk":
            continue
        key = (str(args.get("body")), int(args.get("node", 0)))
        if args.get("outer_diameter") is not None or args.get("mass") is not None:
            out[key] = dict(args)
        elif key in out:  # an unbalance added to the disk already there
            out[key] = {**out[key], **{k: v for k, v in args.items() if "unbalance" in k}}
    return out


def _equivalent_disk(rigid: Any, e: np.ndarray) -> tuple[float, float]:
    """Diameter and width of the uniform disk with ``rigid``'s mass and inertia about ``e``."""
    m = float(rigid.mass)
    J = np.asarray(rigid.inertia, dtype=float)
    if m <= 0:
        return 0.0, 0.0
    jp = float(e @ J @ e)
    jd = float(np.trace(J) - jp) / 2.0
    d = 2.0 * math.sqrt(max(2.0 * jp / m, 0.0))
    w2 = 12.0 * jd / m - 3.0 * (d / 2) ** 2
    return d, math.sqrt(w2) if w2 > 0 else 0.15 * d


def _segments(name: str, body: Any) -> list[Segment]:
    out = []
    pts = np.asarray(body.positions, dtype=float)
    for i, layers in enumerate(body.data.get("layers", [])):
        for j, layer in enumerate(layers):
            if layer.diameters is not None:
                o0, i0, o1, i1 = layer.diameters
                outer, inner, section = (o0, o1), (i0, i1), False
            elif layer.section is not None:
                do, di, section = section_diameters(layer.section)
                outer, inner = (do, do), (di, di)
            else:
                continue
            out.append(Segment(name, i, pts[i], pts[i + 1], outer, inner, j, section))
    return out


def section_diameters(section: Any) -> tuple[float, float, bool]:
    """``(outer, inner, non_circular)``: the tube of a circular section (``Iy = Iz``, from
    ``A`` and ``I``), else the full circle of the same area, flagged.

    >>> from rheolin.mechanics.sections import hollow_circular
    >>> [round(x, 6) for x in section_diameters(hollow_circular(0.05, 0.03))[:2]]
    [0.05, 0.03]
    """
    A, Iy, Iz = float(section.area), float(section.Iy), float(section.Iz)
    if abs(Iy - Iz) <= 1e-6 * max(Iy, Iz):
        sum_sq = 16.0 * Iy / A  # D^2 + d^2
        diff_sq = 4.0 * A / math.pi  # D^2 - d^2
        inner_sq = max(0.5 * (sum_sq - diff_sq), 0.0)
        return math.sqrt(0.5 * (sum_sq + diff_sq)), math.sqrt(inner_sq), False
    return math.sqrt(4.0 * A / math.pi), 0.0, True


def _pitch(mesh: dict[str, Any], teeth: int) -> float:
    return teeth * float(mesh["module"]) / max(math.cos(float(mesh.get("helix_angle", 0.0))), 1e-9)


def model_geometry(model: Any) -> Geometry:
    """The shapes of ``model`` (a :class:`~rheolin.mechanics.Model`) for its drawing."""
    try:
        plan = model.speed_plan()
        ratios = {b: float(r) for b, r in plan.ratios.items()}
    except Exception:  # a model whose speeds cannot be resolved is still drawn
        ratios = {}
    geo = Geometry(
        axes={n: np.asarray(b.axis, dtype=float) for n, b in model.bodies.items()},
        nodes={n: np.asarray(b.positions, dtype=float) for n, b in model.bodies.items()},
        kinds={n: str(b.kind) for n, b in model.bodies.items()},
        speed_ratios=ratios,
    )
    gears: dict[tuple[str, int], tuple[str, int, float]] = {}
    for name, mesh in model.meshes.items():
        pair = mesh["pair"]
        p = (pair.pinion_body, int(mesh["pinion_node"]))
        g = (pair.gear_body, int(mesh["gear_node"]))
        dp, dg = _pitch(mesh, pair.pinion_teeth), _pitch(mesh, pair.gear_teeth)
        gears.setdefault(p, (name, pair.pinion_teeth, dp))
        gears.setdefault(g, (name, pair.gear_teeth, dg))
        geo.meshes.append(
            MeshShape(
                name,
                p,
                g,
                geo.nodes[p[0]][p[1]],
                geo.nodes[g[0]][g[1]],
                pair.pinion_teeth,
                pair.gear_teeth,
                dp,
                dg,
                bool(getattr(pair, "internal", False)),
            )
        )
    calls = _disk_calls(model)
    for name, body in model.bodies.items():
        e = geo.axes[name]
        if body.kind == "shaft":
            geo.segments += _segments(name, body)
        if body.kind == "condensed":
            geo.condensed_modes[name] = int(getattr(body.data.get("condensed"), "n_modes", 0))
        for node, rigid in body.disks.items():
            args = calls.get((name, int(node)), {})
            centre = geo.nodes[name][node] + float(args.get("axial_offset", 0.0) or 0.0) * e
            if args.get("outer_diameter") is not None:
                outer = float(args["outer_diameter"])
                width = float(args.get("width") or 0.1 * outer)
                inner = float(args.get("inner_diameter") or 0.0)
            else:
                outer, width = _equivalent_disk(rigid, e)
                inner = 0.0
            gear = gears.get((name, int(node)))
            unbalance = bool(args.get("unbalance") or args.get("couple_unbalance"))
            geo.disks.append(
                DiskShape(
                    name,
                    int(node),
                    centre,
                    outer,
                    inner,
                    width,
                    mesh=None if gear is None else gear[0],
                    teeth=None if gear is None else gear[1],
                    pitch=None if gear is None else gear[2],
                    unbalance=unbalance,
                )
            )
    for key, (mesh_name, teeth, pitch) in gears.items():
        if not any((d.body, d.node) == key for d in geo.disks):  # a gear without a blank
            width = 0.25 * pitch
            centre = geo.nodes[key[0]][key[1]]
            geo.disks.append(
                DiskShape(key[0], key[1], centre, pitch, 0.0, width, mesh_name, teeth, pitch)
            )
    for name, j in model.joints.items():
        geo.supports.append(
            _support(geo, name, j, _local(j.get("components"), geo.axes[j["body"]]))
        )
    for name, r in model.rolling.items():
        law = getattr(r.get("law"), "kind", None) or "rolling"
        geo.supports.append(_support(geo, name, r, ["ux", "uy"], rolling=str(law)))
    for name, link in model.links.items():
        a = geo.nodes[link["body"]][link["node"]]
        b = geo.nodes[link["other_body"]][link["other_node"]]
        geo.links.append(LinkShape(name, a, b))
    for name, t in model.torques.items():
        geo.torques[name] = (t["body"], int(t["node"]), t["torque"])
    return geo


def _support(
    geo: Geometry, name: str, j: dict[str, Any], components: Any, rolling: str | None = None
) -> Support:
    body, node = j["body"], int(j["node"])
    point = geo.nodes[body][node] + np.asarray(j.get("offset") or np.zeros(3), dtype=float)
    other_body, other_node = j.get("other", (None, None))
    other = other_point = None
    if other_body is not None:
        other = (other_body, int(other_node))
        off = np.asarray(j.get("other_offset") or np.zeros(3), dtype=float)
        other_point = geo.nodes[other_body][int(other_node)] + off
    kind = support_kind(components)
    return Support(name, body, node, point, kind, other, other_point, rolling)
