"""A step's figure: its tab's plots in order, titled as the tab, legends naming the curves drawn."""

from __future__ import annotations

from validation.studies.demo import plot_title, step_curves, step_figure, step_plots


def test_each_figure_draws_its_tab(step_runs):
    """A step's figure has its tab's plots in order, titled as the tab, and its legends name
    exactly the curves drawn."""
    for run in step_runs:
        drawing = step_figure(run)
        plots = step_plots(run.step, run.scene, run.two_plants)
        axes = drawing.figure.axes
        assert len(axes) == len(plots)
        for ax, plot in zip(axes, plots, strict=True):
            assert ax.get_title(loc="left") == plot_title(plot, run.step, run.scene)
            want = [n for c in step_curves(run, plot) if c.t.size for n in c.names]
            legend = ax.get_legend()
            got = [t.get_text() for t in legend.get_texts()] if legend else []
            assert got == want, (run.step.prefix, plot)
