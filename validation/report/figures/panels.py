"""What the figures draw into a panel: curves on a log axis with the threshold (:func:`log_panel`;
an identically zero curve is left out and named, a log axis has no place for zero), the curves of
coinciding plants told apart by markers staggered in time, legends outside the data; the series as
their checks see them; and :func:`prepare_drawing`, one throw-away figure drawn with these helpers."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from analytic.threshold import Threshold
from validation.compare.checks import Check, Comparison, Series, Subject
from validation.report.figures.drawing import Drawing, FigureFormat
from validation.report.figures.layout import finish_axes, new_figure, title_panel
from validation.report.figures.style import THRESHOLD_STYLE, plant_style

MARKERS_PER_CURVE = 12  # markers on each curve, staggered between curves so coinciding ones show
_SUPERSCRIPT = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")


def _power_of_ten(x: float, pos: int | None = None) -> str:
    """A log axis' tick label in plain text: ``1e-12`` -> ``10⁻¹²`` (other values as ``%g``)."""
    if not (x > 0 and math.isfinite(x)):
        return ""
    e = round(math.log10(x))
    if math.isclose(x, 10.0**e, rel_tol=1e-9):
        return "10" + str(e).translate(_SUPERSCRIPT)
    return f"{x:g}"


def _markevery(n: int, k: int) -> tuple[int, int]:
    """Every ``n // MARKERS_PER_CURVE``-th sample, the k-th curve offset by a third of that."""
    step = max(n // MARKERS_PER_CURVE, 1)
    return ((k * step) // 3 % step, step)


def _line(ax, t: np.ndarray, v: np.ndarray, subject: Subject, k: int, label: str, **kw):
    style = plant_style(subject)
    style.update(kw)
    return ax.plot(
        t,
        v,
        label=label,
        linewidth=1.0,
        markersize=4,
        markerfacecolor="none",
        markevery=_markevery(len(t), k),
        **style,
    )[0]


def log_axis(ax, values: Sequence[np.ndarray]) -> None:
    """A log y axis with limits a factor 5 beyond the positive finite ``values``, set before any
    line is drawn (autoscale would warn on a constant series, such as a threshold alone); decades
    labelled ``10⁻¹²`` (:func:`_power_of_ten`), minor ticks unlabelled (the limits span more than
    a decade, so at least one decade is labelled)."""
    from matplotlib.ticker import NullFormatter

    pos = [np.asarray(v, float).ravel() for v in values]
    allpos = np.concatenate(pos) if pos else np.zeros(0)
    allpos = allpos[(allpos > 0) & np.isfinite(allpos)]
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(_power_of_ten)
    ax.yaxis.set_minor_formatter(NullFormatter())
    if allpos.size:
        ax.set_ylim(allpos.min() / 5, allpos.max() * 5)
    else:
        ax.set_ylim(1e-16, 1.0)
    ax.grid(True, which="major", alpha=0.3)


def log_panel(
    ax, curves: Sequence[tuple[Subject, np.ndarray, np.ndarray]], threshold: float | None
) -> list[Subject]:
    """Positive values on a log axis; returns the subjects whose curve is identically zero (not
    drawn: a log axis has no place for zero, the caption says so)."""
    limit = [np.array([threshold])] if threshold is not None and threshold > 0 else []
    log_axis(ax, [np.asarray(v, float) for _, _, v in curves] + limit)
    zero: list[Subject] = []
    for k, (subject, t, values) in enumerate(curves):
        v = np.asarray(values, float)
        if not np.any(v):
            zero.append(subject)
            continue
        _line(ax, t, np.where(v > 0, v, np.nan), subject, k, subject.value)
    if limit:
        ax.axhline(threshold, label="threshold", **THRESHOLD_STYLE)
    return zero


def figure_legend(fig, axes) -> None:
    """One legend for the whole figure, in the row kept for it below the panels (every panel
    shows the same curves); then the axes are finished (:func:`finish_axes`)."""
    handles: dict[str, Any] = {}
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(lab, h)
    if handles:
        fig.legend(
            list(handles.values()),
            list(handles),
            loc="lower center",
            bbox_to_anchor=(0.5, 0.0),
            ncols=min(len(handles), 4),
            fontsize=9,
            frameon=False,
        )
    finish_axes(fig, axes)


def side_legend(ax) -> None:
    """A legend to the right of the panel, outside the data."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize=8)


def prepare_drawing() -> None:
    """Draw and encode one small throw-away figure with the figures' own helpers, so that what a
    process's first figure would otherwise load while it draws (the fonts at the figures' sizes,
    glyph and text-layout caches, the log-axis tick machinery, the PNG encoder) is loaded now.

    ``tumble validate`` calls it at idle priority while the plants run; the evidence workers
    forked afterwards inherit all of it, and their first figure costs what a second one would
    (``docs/performance.md``, Report figures)."""
    fig, axes = new_figure(1, "prepare")
    t = np.linspace(0.0, 1.0, 5)
    log_panel(axes[0], [(Subject.BOTH, t, 10.0**-t)], 1e-3)
    axes[0].set_ylabel("m")
    title_panel(axes[0], "prepare")
    axes[-1].set_xlabel("t (s)")
    figure_legend(fig, axes)
    Drawing("prepare", "", fig).render(FigureFormat.PNG)


def checks_by_series(cmp: Comparison) -> dict[str, Check]:
    return {c.series: c for c in cmp.checks if c.series}


def as_checked(s: Series, checks: Mapping[str, Check]) -> np.ndarray:
    """The series as its check sees it: divided by the check's scale for a relative check."""
    c = checks.get(s.key)
    return s.values / c.scale if c is not None and c.scale > 0 else s.values


def threshold_of(cmp: Comparison, name: str) -> Threshold | None:
    return cmp.thresholds.get(name)


def plant_rows(cmp: Comparison, names: Sequence[str]) -> list[tuple[str, list[Series]]]:
    rows = []
    for name in names:
        ss = [s for s in cmp.series if not s.subject.is_pair and s.name == name]
        if ss:
            rows.append((name, ss))
    return rows


__all__ = [
    "as_checked",
    "checks_by_series",
    "figure_legend",
    "log_axis",
    "log_panel",
    "plant_rows",
    "prepare_drawing",
    "side_legend",
    "threshold_of",
]
