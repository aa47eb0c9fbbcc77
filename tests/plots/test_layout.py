"""The figure checks of rheolin.plots.layout against figures whose geometry is known: texts
placed on top of each other or apart, panels with and without data, legends for artists
that draw nothing."""

from __future__ import annotations

import numpy as np

from rheolin.plots._common import new_figure
from rheolin.plots.layout import (
    drop_overlapping,
    empty_axes,
    has_data,
    overlaps,
    phantom_legend_entries,
    problems,
)


def _panel():
    fig, axes = new_figure(1, 1, (6, 4))
    ax = axes[0, 0]
    ax.plot([0, 1], [0, 1])
    return fig, ax


def test_texts_overlap_exactly_when_their_boxes_meet():
    """Two labels at the same point overlap; 0.4 of the panel apart (about 190 px, far more
    than a 10-character label at 10 pt) they do not."""
    fig, ax = _panel()
    ax.text(0.1, 0.5, "label one", transform=ax.transAxes)
    ax.text(0.1, 0.5, "label two", transform=ax.transAxes)
    assert overlaps(fig) == [("label one", "label two")]
    fig, ax = _panel()
    ax.text(0.1, 0.5, "label one", transform=ax.transAxes)
    ax.text(0.5, 0.5, "label two", transform=ax.transAxes)
    assert overlaps(fig) == []


def test_a_label_off_the_figure_and_crowded_ticks_are_found():
    fig, ax = _panel()
    ax.text(1.3, 0.5, "outside", transform=ax.transAxes)
    assert ("outside", "<figure edge>") in overlaps(fig)
    fig, axes = new_figure(1, 1, (1.5, 3))  # 100 ticks on a 1.5-inch axis cannot fit
    axes[0, 0].plot(np.arange(100.0), np.arange(100.0))
    axes[0, 0].set_xticks(np.arange(100.0))
    assert len(overlaps(fig)) > 50


def test_reference_lines_alone_leave_a_panel_empty():
    fig, axes = new_figure(1, 2, (6, 3))
    empty, full = axes[0]
    empty.axhline(0.0)
    empty.axvspan(0.2, 0.4)
    empty.text(0.5, 0.5, "nothing here", transform=empty.transAxes)
    full.scatter([1.0], [2.0])
    assert not has_data(empty) and has_data(full)
    assert empty_axes(fig) == [empty]


def test_data_outside_the_view_does_not_count():
    _fig, ax = _panel()
    ax.lines[0].remove()
    ax.plot([10.0, 11.0], [10.0, 11.0])
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    assert not has_data(ax)


def test_a_legend_entry_for_an_empty_artist_is_reported():
    fig, ax = _panel()
    ax.plot([], [], "o", label="unstable")
    ax.plot([0.5], [0.5], "s", label="drawn")
    ax.legend()
    assert phantom_legend_entries(fig) == ["unstable"]
    assert problems(fig) == ["legend entry not drawn: unstable"]


def test_drop_overlapping_keeps_the_first_and_the_fixed_artists():
    fig, ax = _panel()
    title = ax.set_title("a title")
    a = ax.text(0.1, 0.5, "first", transform=ax.transAxes)
    b = ax.text(0.1, 0.5, "second", transform=ax.transAxes)
    c = ax.text(0.6, 0.5, "third", transform=ax.transAxes)
    under = ax.annotate("under the title", (0.5, 1.0), xycoords="axes fraction", va="bottom",
                        ha="center")  # fmt: skip
    assert drop_overlapping([a, b, c, under], keep=[title]) == [a, c]
    assert not b.get_visible() and not under.get_visible()
    assert problems(fig) == []
