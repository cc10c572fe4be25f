"""The text of ``demo.md`` (:func:`demo_markdown`): the learning goals, how to open the recording,
each step's story with its key plot, figure and what to look at, the exercises, the paper."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from analytic.scene import Scene
from analytic.trajectory import Trajectory
from validation.studies.demo.chapters import EXERCISES, LEARNING_GOALS, PAPER
from validation.studies.demo.step import DemoStep, is_controlled, plot_title, step_plots


def demo_markdown(
    runs: list[tuple[DemoStep, Scene, Trajectory]],
    t_end: float,
    rtol: float,
    two_plants: bool,
    shown: Path | str = "demo.rrd",
    bodies: list[str] | None = None,
    figures: Sequence[str] | None = None,
) -> str:
    """The text of ``demo.md``: goals, how to open the recording, the steps with what to look
    at, exercises, and the paper. ``bodies[i]``, when given, is step i's text as its recording
    shows it (:func:`validation.recording.recording.narrative_for`: the narrative with the arrow scales,
    colours and exaggeration factors); ``figures[i]``, when given, the file name of step i's
    figure (:func:`step_figure`), embedded in its section."""
    ghost = (
        "; the MuJoCo twin under the same controller as an orange wireframe over the analytic "
        "body, and beside it with its difference exaggerated, RK4 at the scene's timestep, its "
        "curves in the same plots"
        if two_plants
        else ""
    )
    md = [
        "# tumble demo: a tumbling body with sliding masses, free and under exact control",
        "",
        f"Based on {PAPER} Equation, remark and figure numbers below are the paper's.",
        "",
        "# Learning goals",
        "",
        "After the four steps you can",
        "",
        *[f"{i}. {g}" for i, g in enumerate(LEARNING_GOALS, 1)],
        "",
        "# Opening the recording",
        "",
        f"    rerun {shown}",
        "",
        "opens it in the Rerun viewer (version 0.41, installed with this package). One tab per "
        f"step, {t_end:g} s each (analytic plant, DOP853 at rtol {rtol:g}{ghost}). Press play "
        "in the time panel at the bottom, or drag its cursor. In each tab the body is on the left "
        "(green arrow: ω; purple: the control torque τ; the line: the path of C) above the "
        "step's text; on the right the step's key plot on top, with two thirds of the height, and "
        "the others below. Errors and drifts are plotted as log10 (Rerun has no log axis; an "
        "exact zero is not plotted)."
        + (
            " Each step's plots are also drawn as a figure in its section below, for reading "
            "without the viewer."
            if figures
            else ""
        ),
        "",
        "# The four steps",
        "",
    ]
    for i, (step, sc, _) in enumerate(runs):
        # the narrative without its own heading (with the recording's legend when given)
        body = (bodies[i] if bodies else step.narrative).split("\n\n", 1)[1]
        plots = step_plots(step, sc, two_plants)
        md += [f"## {step.title}", "", body, ""]
        md += [f"**Key plot:** {plot_title(plots[0], step, sc)}.", ""] if plots else []
        if figures:
            alt = f"{step.title}: " + "; ".join(plot_title(p, step, sc) for p in plots)
            md += [f"![{alt}]({figures[i]})", ""]
        if step.look_at:
            md += ["**What to look at:**", "", *[f"- {x}" for x in step.look_at], ""]
        if not is_controlled(sc):
            md += ["No control acts in this step, so its tab has no control plot.", ""]
    md += [
        "# Exercises",
        "",
        "Each asks for a prediction first; the answer's physics follows it. The numbers are for "
        "the scene's 20 s horizon.",
        "",
    ]
    for i, (title, text) in enumerate(EXERCISES, 1):
        md += [f"**Exercise {i}. {title}.** {text}", ""]
    md += ["# Reference", "", PAPER, ""]
    return "\n".join(md)


__all__ = ["demo_markdown"]
