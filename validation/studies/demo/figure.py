"""A step's figure (:func:`step_figure`): its tab's plots drawn with matplotlib, for reading without
a viewer, written as ``{prefix}.png`` (:func:`write_step_figures`)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from validation.report.figures import Drawing, FigureFormat
from validation.runs.atomic import write_bytes
from validation.studies.demo.curves import Curves, step_curves
from validation.studies.demo.plots import LOG_PLOTS, Plot
from validation.studies.demo.runs import StepRun
from validation.studies.demo.step import plot_title, step_plots

FIGURE_DPI = 150  # pixels per inch of a step's PNG
FIGURE_WIDTH_IN = 11.0  # in: the panels and, right of them, their legends
FIGURE_ROW_IN = 1.9  # in: the height of a plot (the key plot has two)
FIGURE_LEGEND_IN = 3.4  # in: room right of the panels for the legends
FIGURE_GAP_IN = 0.45  # in: between panels, for the lower one's title


def step_figure(run: StepRun):
    """The figure of one step (a :class:`validation.report.figures.Drawing`): its tab's plots in the
    tab's order, the key plot first with twice the height, each titled as in the recording, every
    curve named in a legend beside its panel."""
    from matplotlib.figure import Figure

    plots = step_plots(run.step, run.scene, run.two_plants)
    ratios = [2.0] + [1.0] * (len(plots) - 1)
    top, bottom = 0.75, 0.55
    height = FIGURE_ROW_IN * sum(ratios) + top + bottom + FIGURE_GAP_IN * (len(plots) - 1)
    fig = Figure(figsize=(FIGURE_WIDTH_IN, height), dpi=FIGURE_DPI)
    axes = fig.subplots(
        len(plots),
        1,
        sharex=True,
        squeeze=False,
        gridspec_kw={
            "height_ratios": ratios,
            "left": 0.85 / FIGURE_WIDTH_IN,
            "right": 1.0 - FIGURE_LEGEND_IN / FIGURE_WIDTH_IN,
            "top": 1.0 - top / height,
            "bottom": bottom / height,
            "hspace": FIGURE_GAP_IN / (FIGURE_ROW_IN * sum(ratios) / len(plots)),
        },
    )[:, 0]
    fig.suptitle(run.step.title, fontsize=12, x=0.85 / FIGURE_WIDTH_IN, ha="left")
    titles = []
    for ax, plot in zip(axes, plots, strict=True):
        titles.append(plot_title(plot, run.step, run.scene))
        _draw_panel(ax, plot, step_curves(run, plot), titles[-1])
    axes[-1].set_xlabel("t (s)")
    return Drawing(run.step.prefix, f"{run.step.title}: " + "; ".join(titles) + ".", fig)


def _draw_panel(ax, plot: Plot, curves: Sequence[Curves], title: str) -> None:
    """One plot of a step's figure: every column of every :class:`Curves`, with its name."""
    for c in curves:
        if not c.t.size:
            continue
        v = np.asarray(c.values, float).reshape(len(c.t), -1)
        for j, name in enumerate(c.names):
            rgba = tuple(x / 255 for x in c.colors[j])
            ax.plot(
                c.t, v[:, j], color=rgba, linestyle="--" if c.dashed else "-", lw=1.2, label=name
            )
    ax.set_title(title, fontsize=9, loc="left")
    ax.set_ylabel("log10" if plot in LOG_PLOTS else _scale_lines(ax))
    ax.grid(True, alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)


def _scale_lines(ax) -> str:
    """Divide a linear panel's lines by a power of ten (a multiple of three) when their values
    reach 1e4, so no offset text sits on the title; the factor, as the y label (``× 1e9``)."""
    peak = max(
        (np.nanmax(np.abs(ln.get_ydata())) for ln in ax.lines if len(ln.get_ydata())), default=0.0
    )
    if not (np.isfinite(peak) and peak >= 1e4):
        return ""
    e = 3 * int(np.floor(np.log10(peak) / 3))
    for ln in ax.lines:
        ln.set_ydata(np.asarray(ln.get_ydata(), float) / 10.0**e)
    ax.relim()
    ax.autoscale_view()
    return f"× 1e{e}"


def write_step_figures(out: Path, runs: Sequence[StepRun]) -> tuple[Path, ...]:
    """Each step's figure as ``{prefix}.png`` in ``out``, written atomically; their paths."""
    return tuple(
        write_bytes(out / f"{r.step.prefix}.png", step_figure(r).render(FigureFormat.PNG))
        for r in runs
    )


__all__ = ["step_figure", "write_step_figures"]
