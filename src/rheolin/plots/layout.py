"""What a reader sees of a figure: the texts drawn and where, overlaps between them, panels
with nothing drawn, legend entries for artists that are not there.

The plots use :func:`drop_overlapping` to keep only the labels that fit; the tests and the
gallery script (``docs/gallery/make.py``) use :func:`problems` to refuse a figure a reader
would struggle with.

>>> from rheolin.plots._common import new_figure
>>> fig, axes = new_figure(1, 2, (6, 3))
>>> _ = axes[0, 0].plot([0, 1], [0, 1], label="a line")
>>> _ = axes[0, 0].legend()
>>> a = axes[0, 0].text(0.5, 0.5, "label one", transform=axes[0, 0].transAxes)
>>> b = axes[0, 0].text(0.5, 0.5, "label two", transform=axes[0, 0].transAxes)
>>> [p.split(":")[0] for p in problems(fig)]
['overlap', 'empty panel']
>>> _ = drop_overlapping([a, b])
>>> axes[0, 1].set_visible(False)
>>> problems(fig)
[]
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import Collection
from matplotlib.figure import Figure
from matplotlib.image import AxesImage
from matplotlib.legend import Legend
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.text import Text
from matplotlib.transforms import Bbox

__all__ = [
    "Drawn",
    "drawn_texts",
    "drop_overlapping",
    "empty_axes",
    "has_data",
    "overlaps",
    "phantom_legend_entries",
    "problems",
]

#: Two texts overlap when their boxes share more than this many pixels in both directions
#: (a glyph's antialiasing fringe does not count).
TOLERANCE_PX = 1.0


@dataclass(frozen=True)
class Drawn:
    """A text (or a legend box) as drawn: what it says, where it is, and what owns it."""

    text: str
    box: Bbox
    owner: Any
    artist: Any


def _renderer(fig: Figure) -> Any:
    if not hasattr(fig.canvas, "get_renderer"):
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        FigureCanvasAgg(fig)
    fig.draw_without_rendering()  # the constrained layout places everything
    return fig.canvas.get_renderer()  # type: ignore[attr-defined]


def _shown(t: Text) -> bool:
    return bool(t.get_visible() and t.get_text().strip() and t.get_alpha() != 0)


def _tick_labels(ax: Axes) -> Iterable[Text]:
    """Tick labels drawn inside the view limits (matplotlib keeps others off screen)."""
    for axis in (ax.xaxis, ax.yaxis):
        scale = axis.get_transform()
        with np.errstate(all="ignore"):
            lo, hi = sorted(scale.transform(np.asarray(axis.get_view_interval(), float)))
            span = hi - lo
            for ticks in (axis.get_major_ticks(), axis.get_minor_ticks()):
                for tick in ticks:
                    loc = tick.get_loc()
                    if loc is None or not tick.get_visible():
                        continue
                    at = float(scale.transform(np.array([float(loc)]))[0])
                    if not (np.isfinite(at) and lo - 1e-9 * span <= at <= hi + 1e-9 * span):
                        continue
                    for label in (tick.label1, tick.label2):
                        if _shown(label):
                            yield label


def drawn_texts(fig: Figure) -> list[Drawn]:
    """Every visible text of ``fig`` with its box in pixels: titles, axis and tick labels,
    annotations, figure texts, and each legend as one box."""
    renderer = _renderer(fig)
    out: list[Drawn] = []
    seen: set[int] = set()

    def add(t: Text, owner: Any) -> None:
        if id(t) not in seen and _shown(t):
            seen.add(id(t))
            box = t.get_window_extent(renderer)
            if box.width > 0 and box.height > 0:
                out.append(Drawn(t.get_text(), box, owner, t))

    for child in fig.get_children():
        if isinstance(child, Text):
            add(child, fig)
    for t in fig.texts:
        add(t, fig)
    for legend in fig.legends:
        out.append(Drawn("<legend>", legend.get_window_extent(renderer), fig, legend))
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        titles = (ax.title, getattr(ax, "_left_title", None), getattr(ax, "_right_title", None))
        for title in titles:  # matplotlib keeps the left and right titles unlisted
            if isinstance(title, Text):
                add(title, ax)
        if ax.name != "3d":
            add(ax.xaxis.label, ax)
            add(ax.yaxis.label, ax)
            add(ax.xaxis.get_offset_text(), ax)
            add(ax.yaxis.get_offset_text(), ax)
            for t in _tick_labels(ax):
                add(t, ax)
        for t in ax.texts:
            add(t, ax)
        for child in ax.get_children():  # ax.get_legend() and any added by add_artist
            if isinstance(child, Legend) and child.get_visible():
                out.append(Drawn("<legend>", child.get_window_extent(renderer), ax, child))
    return out


def _intersect(a: Bbox, b: Bbox, tol: float = TOLERANCE_PX) -> bool:
    w = min(a.x1, b.x1) - max(a.x0, b.x0)
    h = min(a.y1, b.y1) - max(a.y0, b.y0)
    return w > tol and h > tol


def overlaps(fig: Figure) -> list[tuple[str, str]]:
    """Pairs of drawn texts whose boxes overlap (:data:`TOLERANCE_PX`), and texts that run
    off the figure (paired with ``"<figure edge>"``)."""
    items = drawn_texts(fig)
    edge = fig.bbox
    out = []
    for i, a in enumerate(items):
        inside = (
            a.box.x0 >= edge.x0 - TOLERANCE_PX
            and a.box.y0 >= edge.y0 - TOLERANCE_PX
            and a.box.x1 <= edge.x1 + TOLERANCE_PX
            and a.box.y1 <= edge.y1 + TOLERANCE_PX
        )
        if not inside:
            out.append((a.text, "<figure edge>"))
        for b in items[i + 1 :]:
            if _inside_legend(a, b) or _inside_legend(b, a):
                continue
            if _intersect(a.box, b.box):
                out.append((a.text, b.text))
    return out


def _inside_legend(a: Drawn, b: Drawn) -> bool:
    """``b`` is a text of legend ``a`` (the legend lays its own texts out)."""
    return isinstance(a.artist, Legend) and b.artist in a.artist.get_texts()


def has_data(ax: Axes) -> bool:
    """Whether ``ax`` draws data: a line, marker, collection, image or patch placed in data
    coordinates with something inside the view (reference lines and spans do not count)."""
    if not ax.get_visible():
        return False
    if ax.name == "3d":
        return any(len(np.ravel(line.get_data_3d()[0])) for line in ax.lines)  # type: ignore[attr-defined]
    (x0, x1), (y0, y1) = sorted(ax.get_xlim()), sorted(ax.get_ylim())
    for line in ax.lines:
        if not line.get_visible() or not line.get_transform().contains_branch(ax.transData):
            continue
        x, y = (np.asarray(v, dtype=float) for v in line.get_data())
        inside = np.isfinite(x) & np.isfinite(y) & (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)
        if inside.any():
            return True
    for c in ax.collections:
        if not c.get_visible():
            continue
        data = c.get_transform().contains_branch(ax.transData) or c.get_offset_transform() is (
            ax.transData
        )
        if data and (len(c.get_paths()) or len(np.asarray(c.get_offsets()))):
            return True
    if any(im.get_visible() for im in ax.images if isinstance(im, AxesImage)):
        return True
    return any(
        p.get_visible() and p.get_transform().contains_branch(ax.transData)
        for p in ax.patches
        if isinstance(p, Patch)
    )


def empty_axes(fig: Figure) -> list[Axes]:
    """Visible panels that draw no data (colorbars excepted)."""
    out = []
    for ax in fig.axes:
        if not ax.get_visible() or ax.get_label() == "<colorbar>":
            continue
        if not has_data(ax):
            out.append(ax)
    return out


def phantom_legend_entries(fig: Figure) -> list[str]:
    """Legend labels whose artist in the same panel draws nothing (a legend built from proxy
    artists, which are not in the panel, is not judged)."""
    out = []
    for ax in fig.axes:
        legend = ax.get_legend()
        if legend is None or not legend.get_visible():
            continue
        artists: dict[str, list[Any]] = {}
        for a in [*ax.lines, *ax.collections, *ax.patches]:
            artists.setdefault(str(a.get_label()), []).append(a)
        for t in legend.get_texts():
            found = artists.get(t.get_text())
            if found and not any(_draws(a, ax) for a in found):
                out.append(t.get_text())
    return out


def _draws(a: Any, ax: Axes) -> bool:
    if not a.get_visible():
        return False
    if isinstance(a, Line2D):
        x, y = (np.asarray(v, dtype=float) for v in a.get_data())
        return bool((np.isfinite(x) & np.isfinite(y)).any())
    if isinstance(a, Collection):
        return bool(len(a.get_paths()) or len(np.asarray(a.get_offsets())))
    return True


def problems(fig: Figure) -> list[str]:
    """Everything :mod:`rheolin.plots.layout` finds wrong with ``fig``, one line each:
    ``overlap: 'a' / 'b'``, ``empty panel: <title>``, ``legend entry not drawn: <label>``."""
    out = [f"overlap: {a!r} / {b!r}" for a, b in overlaps(fig)]
    for ax in empty_axes(fig):
        out.append(f"empty panel: {ax.get_title() or ax.get_ylabel() or '(untitled)'}")
    out += [f"legend entry not drawn: {t}" for t in phantom_legend_entries(fig)]
    return out


def drop_overlapping(texts: Sequence[Text], keep: Sequence[Any] = ()) -> list[Text]:
    """Hide every text of ``texts`` that overlaps one kept before it (in the order given: put
    the most important first) or an artist of ``keep`` (titles, legends); returns the texts
    left visible. Call it once the figure is otherwise complete."""
    if not texts:
        return []
    fig = texts[0].get_figure(root=True)
    renderer = _renderer(fig)  # type: ignore[arg-type]
    taken = [a.get_window_extent(renderer) for a in keep if a is not None and a.get_visible()]
    shown = []
    for t in texts:
        if not _shown(t):
            continue
        box = t.get_window_extent(renderer)
        edge = fig.bbox  # type: ignore[union-attr]
        inside = edge.x0 <= box.x0 and box.x1 <= edge.x1 and edge.y0 <= box.y0 and box.y1 <= edge.y1
        if not inside or any(_intersect(box, b) for b in taken):
            t.set_visible(False)
            continue
        taken.append(box)
        shown.append(t)
    return shown
