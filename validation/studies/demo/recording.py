"""A step in ``demo.rrd``: its tab (:func:`step_layout`: the 3D views and the narrative on the left,
the key plot and the others on the right) and what is logged under its prefix (:func:`log_step`)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from analytic.scene import Scene
from analytic.trajectory import Trajectory
from validation.compare.checks import Comparison
from validation.recording.layout import views_3d
from validation.recording.recording import log_run
from validation.recording.style import viewer_text
from validation.recording.world import difference_factors
from validation.studies.demo.curves import Curves, step_curves
from validation.studies.demo.plots import Plot
from validation.studies.demo.runs import StepRun
from validation.studies.demo.step import DemoStep, plot_title, step_narrative, step_plots


def step_layout(
    step: DemoStep,
    scene: Scene,
    two_plants: bool,
    comparison: Comparison | None = None,
    trajectories: Sequence[Trajectory] = (),
):
    """The tab of one step: the 3D views (the plants overlaid and, with MuJoCo, its difference
    from the analytic body exaggerated by the factor the recording logs, from ``comparison`` and
    ``trajectories``) over the narrative on the left; on the right the key plot with two thirds
    of the height (the whole column when alone), the other plots below it."""
    # deferred: rerun ~0.3 s, matplotlib ~0.25 s (python -X importtime): only to write
    import rerun.blueprint as rrb

    p0 = f"/{step.prefix}"
    plots = step_plots(step, scene, two_plants)
    views = [
        rrb.TimeSeriesView(
            origin=f"{p0}/plots/{p.value}", name=viewer_text(plot_title(p, step, scene))
        )
        for p in plots
    ]
    rest = len(views) - 1
    right = rrb.Vertical(*views, row_shares=[2 * rest] + [1] * rest) if rest else views[0]
    names = ("analytic", "mujoco") if two_plants else ("analytic",)
    factors = difference_factors(scene, comparison, names, trajectories)
    left = rrb.Vertical(
        views_3d(p0, names, factors),
        rrb.TextDocumentView(origin=f"{p0}/narrative", name="what to look at"),
        row_shares=[3, 2],
    )
    return rrb.Horizontal(left, right, column_shares=[1, 1], name=viewer_text(step.title))


def _log_curves(rec, origin: str, curves: Sequence[Curves]) -> None:
    """Each :class:`Curves` as scalars under ``origin/entity``, one named, coloured line per
    column (nothing for an empty one)."""
    import rerun as rr

    for c in curves:
        if not c.t.size:
            continue
        v = np.asarray(c.values, float).reshape(len(c.t), -1)
        path = f"{origin}/{c.entity}"
        names = [viewer_text(x) for x in c.names]
        rec.log(path, rr.SeriesLines(names=names, colors=list(c.colors)), static=True)
        rec.send_columns(
            path,
            indexes=[rr.TimeColumn("sim_time", duration=c.t)],
            columns=rr.Scalars.columns(scalars=np.ravel(v)).partition([v.shape[1]] * v.shape[0]),
        )


def log_step(rec, run: StepRun) -> None:
    """Log one step into the recording ``rec`` under its prefix: the run (bodies, plots, the
    narrative; :func:`validation.recording.recording.log_run`) and the demo's own plots."""
    log_run(
        rec,
        run.scene,
        list(run.plants),
        run.comparison,
        narrative=step_narrative(run.step),
        prefix=run.step.prefix,
    )
    for plot in (Plot.OMEGA, Plot.MASS_POSITIONS, Plot.INVARIANTS):
        _log_curves(rec, f"/{run.step.prefix}/plots/{plot.value}", step_curves(run, plot))


__all__ = ["log_step", "step_layout"]
