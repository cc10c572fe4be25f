"""The teaching demo (``tumble demo``): four narrated steps in one Rerun recording, and a guide.

:func:`write_demo` writes ``demo.rrd`` (one tab per step) and ``demo.md``: learning goals, how to
open the recording, each step's story with what to look at, exercises with the physics of their
answers, and the paper's citation. Each step runs on the analytic plant and, when the MuJoCo twin
is importable, on MuJoCo under the same controller, drawn as a translucent ghost and checked
against the analytic plant under the report's thresholds.

Each tab gives the step's *key plot* (:class:`DemoStep.key`) the larger share of the plot column;
a step without control shows no control plot (its torque and rod forces are identically zero,
though the recording keeps them under ``plots/control``).

One job per module: the steps' text (:mod:`.chapters`: a new chapter is one entry of
:data:`STEPS`), a step and what its tab shows (:mod:`.step`), the plots and colours (:mod:`.plots`),
the runs (:mod:`.runs`), the curves each plot draws (:mod:`.curves`), the recording's tabs
(:mod:`.recording`), the figures (:mod:`.figure`), the guide ``demo.md`` (:mod:`.guide`) and the
command writing them all (:mod:`.writer`).
"""

from validation.studies.demo.chapters import EXERCISES, LEARNING_GOALS, PAPER, STEPS
from validation.studies.demo.curves import Curves, step_curves
from validation.studies.demo.figure import step_figure, write_step_figures
from validation.studies.demo.guide import demo_markdown
from validation.studies.demo.plots import (
    CONTROL_PLOTS,
    REQUIREMENT_HUE,
    SERIES_HUES,
    WITH_HUE,
    WITHOUT_HUE,
    Hue,
    Plot,
)
from validation.studies.demo.recording import log_step, step_layout
from validation.studies.demo.runs import DEMO_RTOL, DEMO_T_END, StepRun, run_steps
from validation.studies.demo.step import (
    DemoStep,
    is_controlled,
    plot_title,
    step_narrative,
    step_plots,
    step_scene,
)
from validation.studies.demo.writer import DemoResult, write_demo

__all__ = [
    "CONTROL_PLOTS",
    "DEMO_RTOL",
    "DEMO_T_END",
    "EXERCISES",
    "LEARNING_GOALS",
    "PAPER",
    "REQUIREMENT_HUE",
    "SERIES_HUES",
    "STEPS",
    "WITHOUT_HUE",
    "WITH_HUE",
    "Curves",
    "DemoResult",
    "DemoStep",
    "Hue",
    "Plot",
    "StepRun",
    "demo_markdown",
    "is_controlled",
    "log_step",
    "plot_title",
    "run_steps",
    "step_curves",
    "step_figure",
    "step_layout",
    "step_narrative",
    "step_plots",
    "step_scene",
    "write_demo",
    "write_step_figures",
]
