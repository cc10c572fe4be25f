"""A figure's page, laid out once in inches from its size: panels stacked over a shared time axis
(:func:`new_figure`), titles at a set height (:func:`title_panel`), y labels at one offset measured
from the widest tick label, ticks made only inside the view (:func:`finish_axes`). No layout
engine, no automatic title placement: each would lay every text out several times over
(``docs/performance.md``, Report figures)."""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from validation.report.figures.drawing import PNG_DPI

WIDTH_IN = 10.0  # figure width, in
ROW_IN = 2.3  # height of one panel, in


@dataclass(frozen=True)
class _Layout:
    """Fixed margins of a figure, in inches (figure width :data:`WIDTH_IN`).

    Attributes:
        left_in: room left of the panels for the y tick labels and label (widened when a tick
            label needs more, :func:`_place_axis_labels`).
        right_in: room right of the panels (a side legend's width, or a small margin).
        top_in: room above the first panel: the figure's title and the panel's title.
        gap_in: room between panels: the lower panel's title.
        bottom_in: room below the last panel: x tick labels, the x label and the figure legend.
    """

    left_in: float = 0.9
    right_in: float = 0.25
    top_in: float = 0.62
    gap_in: float = 0.4
    bottom_in: float = 0.55


FIGURE_LEGEND_IN = 0.3  # height of the one-row legend below the panels, in
SIDE_LEGEND_IN = 1.8  # width reserved right of the panels for their side legends, in
SUPTITLE_TOP_IN = 0.08  # from the figure's top edge to its title's top, in
TITLE_PAD_PT = 5.0  # from a panel's top edge to its title's baseline, points
FIGURE_TITLE_PT = 12.0  # font sizes, points
PANEL_TITLE_PT = 10.0


def new_figure(
    nrows: int,
    title: str,
    height_rows: Sequence[float] | None = None,
    *,
    side_legends: bool = False,
):
    """A figure of ``nrows`` panels stacked over a shared time axis, laid out once in inches: a
    legend row below the panels, or with ``side_legends`` room on the right for one legend per
    panel."""
    from matplotlib.figure import Figure

    ratios = list(height_rows) if height_rows is not None else [1.0] * nrows
    layout = _Layout(
        right_in=SIDE_LEGEND_IN if side_legends else _Layout.right_in,
        bottom_in=_Layout.bottom_in + (0.0 if side_legends else FIGURE_LEGEND_IN),
    )
    height = ROW_IN * sum(ratios) + 1.0
    fig = Figure(figsize=(WIDTH_IN, height), dpi=PNG_DPI)
    panels_in = height - layout.top_in - layout.bottom_in - (nrows - 1) * layout.gap_in
    axes = fig.subplots(
        nrows,
        1,
        sharex=True,
        squeeze=False,
        gridspec_kw={
            "left": layout.left_in / WIDTH_IN,
            "right": 1.0 - layout.right_in / WIDTH_IN,
            "top": 1.0 - layout.top_in / height,
            "bottom": layout.bottom_in / height,
            "hspace": layout.gap_in / (panels_in / nrows),
            "height_ratios": ratios,
        },
    )[:, 0]
    fig.suptitle(title, fontsize=FIGURE_TITLE_PT, y=1.0 - SUPTITLE_TOP_IN / height, va="top")
    return fig, axes


def title_panel(ax, text: str) -> None:
    """The panel's title, left, at a set height above it (no search for overlapping labels:
    the layout leaves it room)."""
    ax.set_title(text, fontsize=PANEL_TITLE_PT, loc="left", y=1.0, pad=TITLE_PAD_PT)


@functools.lru_cache(maxsize=512)
def _text_size_pt(text: str, size: float | str) -> tuple[float, float]:
    """(width, height) of one line of ``text`` in the default font at ``size``, points (cached:
    the figures use matplotlib's default font throughout)."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import text_to_path

    prop = FontProperties(size=size)
    w, h, _ = text_to_path.get_text_width_height_descent(text, prop, ismath=False)
    _, lp, _ = text_to_path.get_text_width_height_descent("lp", prop, ismath=False)
    return w, max(h, lp)


def _widest_ytick_label_pt(ax) -> float:
    """Width of the widest major y tick label the panel will draw, points (0 if none)."""
    import matplotlib as mpl

    lo, hi = sorted(ax.get_ybound())
    locs = [v for v in ax.yaxis.get_majorticklocs() if lo <= v <= hi]
    if not locs:
        return 0.0
    size = mpl.rcParams["ytick.labelsize"]
    return max(_text_size_pt(s, size)[0] for s in ax.yaxis.get_major_formatter().format_ticks(locs))


def _in_view(base):
    """``base``, a tick locator, keeping only the ticks inside the view: matplotlib makes a tick
    object (two lines, a grid line, two labels) for every location its locator returns, drawn or
    not, and the usual locators return one beyond each end. (A class made here, not at import:
    this module imports matplotlib only when it draws.)"""
    from matplotlib.ticker import Locator

    class InView(Locator):
        def set_axis(self, axis):
            super().set_axis(axis)
            base.set_axis(axis)

        def __call__(self):
            return self._inside(base(), *self.axis.get_view_interval())

        def tick_values(self, vmin, vmax):
            return self._inside(base.tick_values(vmin, vmax), vmin, vmax)

        def nonsingular(self, v0, v1):
            return base.nonsingular(v0, v1)

        def view_limits(self, vmin, vmax):
            return base.view_limits(vmin, vmax)

        def _inside(self, locs, vmin, vmax):
            locs = np.asarray(locs, float)
            if self.axis is None or not locs.size:
                return locs
            to_screen = self.axis.get_transform()  # the scale: log ticks compare in log space
            lo, hi = sorted(to_screen.transform(np.array([vmin, vmax], float)))
            t = to_screen.transform(locs)
            tol = 1e-9 * (hi - lo)
            with np.errstate(invalid="ignore"):
                return locs[(t >= lo - tol) & (t <= hi + tol)]

    return InView()


def finish_axes(fig, axes) -> None:
    """After every panel is drawn into: ticks only inside the view (:func:`_in_view`), and the
    axis labels placed (:func:`_place_axis_labels`)."""
    for ax in axes:
        ax.yaxis.set_major_locator(_in_view(ax.yaxis.get_major_locator()))
    axes[-1].xaxis.set_major_locator(_in_view(axes[-1].xaxis.get_major_locator()))  # shared
    _place_axis_labels(fig, axes)


def _place_axis_labels(fig, axes) -> None:
    """Put every panel's y label at one offset left of the panels, just beyond the widest tick
    label of all panels (aligned, as a layout engine would), widening the left margin if that
    label needs it; the x label below the last panel's tick labels. Fixed positions: matplotlib
    then skips measuring every tick label for them at each draw."""
    import matplotlib as mpl

    rc = mpl.rcParams
    tick_pt = max(rc["ytick.major.size"], rc["ytick.minor.size"]) + rc["ytick.major.pad"]
    widest = max(_widest_ytick_label_pt(ax) for ax in axes)
    offset_in = (tick_pt + widest + rc["axes.labelpad"]) / 72.0
    label_in = _text_size_pt("1 (relative)", rc["axes.labelsize"])[1] / 72.0
    fig_w, fig_h = fig.get_size_inches()
    gs = axes[0].get_subplotspec().get_gridspec()
    need = (offset_in + label_in) / fig_w + 0.1 / fig_w
    if gs.left < need:
        gs.update(left=need)  # repositions the axes of pyplot's figures only
        for ax in axes:
            ax.set_position(ax.get_subplotspec().get_position(fig))
    width_in = (gs.right - gs.left) * fig_w
    for ax in axes:
        ax.yaxis.set_label_coords(-offset_in / width_in, 0.5)
    ax = axes[-1]
    height_in = ax.get_position().height * fig_h
    xtick_in = (
        rc["xtick.major.size"]
        + rc["xtick.major.pad"]
        + _text_size_pt("0", rc["xtick.labelsize"])[1]
        + rc["axes.labelpad"]
    ) / 72.0
    ax.xaxis.set_label_coords(0.5, -xtick_in / height_in)


__all__ = ["ROW_IN", "WIDTH_IN", "finish_axes", "new_figure", "title_panel"]
