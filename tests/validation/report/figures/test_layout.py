"""The figures' fixed layout: nothing clipped or overlapping, every panel's curves and thresholds whole."""

from __future__ import annotations

import itertools

import numpy as np

PX = 0.5  # px: rounding of text extents


def _inside(box, page) -> bool:
    return (
        box.x0 >= page.x0 - PX
        and box.x1 <= page.x1 + PX
        and box.y0 >= page.y0 - PX
        and box.y1 <= page.y1 + PX
    )


def _apart(a, b) -> bool:
    return a.x1 <= b.x0 + PX or b.x1 <= a.x0 + PX or a.y1 <= b.y0 + PX or b.y1 <= a.y0 + PX


def test_nothing_is_clipped_or_overlapping(drawn):
    """The layout is fixed in inches, not searched for: every panel with its title, tick labels
    and axis labels lies inside the figure, below the figure's title and clear of the panels next
    to it; every legend lies inside the figure and outside every panel's data area."""
    for d, renderer in drawn:
        fig, page = d.figure, d.figure.bbox
        panels = [ax.get_tightbbox(renderer) for ax in fig.axes]  # with title, labels, legend
        for ax, box in zip(fig.axes, panels, strict=True):
            assert _inside(box, page), (d.name, ax.get_title(loc="left"))
        for upper, lower in itertools.pairwise(panels):
            assert lower.y1 <= upper.y0 + PX, d.name
        title = next(
            t
            for t in fig.get_children()
            if getattr(t, "get_text", None) and t.get_text() == fig.get_suptitle()
        ).get_window_extent(renderer)
        assert _inside(title, page) and panels[0].y1 <= title.y0 + PX, d.name
        legends = [*fig.legends, *(ax.get_legend() for ax in fig.axes if ax.get_legend())]
        assert legends, d.name
        for legend in legends:
            box = legend.get_window_extent(renderer)
            assert _inside(box, page), d.name
            assert all(_apart(box, ax.bbox) for ax in fig.axes), d.name
        for legend in fig.legends:  # below the panels, their tick and axis labels
            assert legend.get_window_extent(renderer).y1 <= panels[-1].y0 + PX, d.name


def test_every_panel_shows_its_curves_and_thresholds_whole(drawn):
    """Each panel's y limits enclose every curve it draws and its threshold lines (a log panel's
    limits are set from them, not autoscaled)."""
    for d, _ in drawn:
        for ax in d.figure.axes:
            lo, hi = ax.get_ylim()
            for line in ax.lines:
                y = np.asarray(line.get_ydata(), float)
                y = y[np.isfinite(y) & ((y > 0) if ax.get_yscale() == "log" else True)]
                if line.get_label() == "threshold" or ax.get_yscale() == "log":
                    assert y.size, (d.name, line.get_label())
                if y.size:
                    assert lo <= y.min() and y.max() <= hi, (d.name, line.get_label())
