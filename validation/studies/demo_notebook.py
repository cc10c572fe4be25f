"""The teaching demo as a Jupyter notebook (``docs/demo.ipynb``), and what its cells call.

:func:`notebook` builds the notebook from the demo's own text (:mod:`validation.studies.demo`: the
learning goals, each step's story and what to look at, the exercises), so the notebook and
``tumble demo``'s guide say the same; ``python -m validation.studies.demo_notebook docs/demo.ipynb``
rewrites it. Each step's cell calls :func:`show_step`: the step's tab in Rerun's notebook viewer
(the ``rerun-notebook`` widget, installed with the ``notebook`` extra) and its figure below.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

from validation.runs.atomic import write_text
from validation.studies.demo import (
    EXERCISES,
    LEARNING_GOALS,
    PAPER,
    STEPS,
    StepRun,
    log_step,
    step_figure,
    step_layout,
    step_narrative,
)

NOTEBOOK_APP_ID = "tumble_demo_notebook"
"""The Rerun application id of the notebook's recordings (the viewer remembers layouts per id)."""
VIEWER_HEIGHT_PX = 640  # the embedded viewer's height; its width follows the cell


def show_step(run: StepRun) -> None:
    """Show one step in a notebook: its tab in Rerun's notebook viewer (the step logged into a
    recording of its own, the tab's layout active), then its figure (PNG)."""
    # deferred: rerun ~0.6 s with its notebook widget, IPython (python -X importtime); optional
    import rerun as rr
    import rerun.blueprint as rrb
    from IPython.display import Image, display
    from rerun.notebook import Viewer

    layout = step_layout(run.step, run.scene, run.two_plants, run.comparison, run.plants)
    blueprint = rrb.Blueprint(layout, rrb.TimePanel(state="expanded"))
    rec = rr.RecordingStream(NOTEBOOK_APP_ID, recording_id=f"demo-{run.step.prefix}")
    rec.set_log_time_enabled(False)
    viewer = Viewer(recording=rec, blueprint=blueprint, width="auto", height=VIEWER_HEIGHT_PX)
    log_step(rec, run)
    rec.flush()
    viewer.display()
    display(Image(data=step_figure(run).render("png")))


def _markdown(text: str) -> dict[str, Any]:
    return {"cell_type": "markdown", "metadata": {}, "source": text.strip() + "\n"}


def _code(text: str, tags: tuple[str, ...] = ()) -> dict[str, Any]:
    meta: dict[str, Any] = {"tags": list(tags)} if tags else {}
    return {
        "cell_type": "code",
        "execution_count": None,
        "metadata": meta,
        "outputs": [],
        "source": text.strip() + "\n",
    }


INTRO = """# tumble demo: a tumbling body with sliding masses, free and under exact control

Based on {paper} Equation, remark and figure numbers below are the paper's.

This notebook is `tumble demo` cell by cell: each step runs the scene on the analytic plant (and,
when installed, on the MuJoCo twin under the same controller), shows the step in Rerun's viewer
(press play in its time panel) and draws the same plots as a figure below it. It needs the
`notebook` extra: `pip install -e ".[notebook]"` in the repository, then open this file in
Jupyter.

## Learning goals

After the four steps you can

{goals}"""

PARAMETERS = """T_END = 10.0  # s simulated per step, as `tumble demo` (shorter for a quick look)
MUJOCO = True  # also run the MuJoCo twin, drawn as a ghost and compared"""

RUN = """from validation.studies.demo import run_steps
from validation.studies.demo_notebook import show_step

runs, wall_times = run_steps(t_end=T_END, mujoco=MUJOCO)
print(f"{len(runs)} steps run in {sum(wall_times.values()):.1f} s")"""


def notebook() -> dict[str, Any]:
    """The notebook (nbformat 4): the introduction and goals, a parameter cell, the runs, then
    per step its text and a cell showing it, then the exercises and the reference."""
    goals = "\n".join(f"{i}. {g}" for i, g in enumerate(LEARNING_GOALS, 1))
    cells = [
        _markdown(INTRO.format(paper=PAPER, goals=goals)),
        _code(PARAMETERS, ("parameters",)),
        _code(RUN),
    ]
    for i, step in enumerate(STEPS):
        cells.append(
            _markdown("#" + step_narrative(step))
        )  # "## n. ..." under the notebook's title
        cells.append(_code(f"show_step(runs[{i}])  # {step.title}"))
    exercises = "\n\n".join(
        f"**Exercise {i}. {title}.** {text}" for i, (title, text) in enumerate(EXERCISES, 1)
    )
    cells.append(_markdown(f"## Exercises\n\n{exercises}\n\n## Reference\n\n{PAPER}"))
    return {
        "cells": cells,
        "metadata": {
            "kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"},
            "language_info": {"name": "python"},
        },
        "nbformat": 4,
        "nbformat_minor": 5,
    }


def notebook_text() -> str:
    """:func:`notebook` as the file's text (JSON, one-space indent as Jupyter writes it)."""
    nb = notebook()
    for k, cell in enumerate(nb["cells"]):
        cell["id"] = f"cell-{k}"
    return json.dumps(nb, indent=1, ensure_ascii=False) + "\n"


def main(argv: list[str] | None = None) -> int:
    """``python -m validation.studies.demo_notebook PATH``: write the notebook to PATH."""
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1:
        print("usage: python -m validation.studies.demo_notebook PATH.ipynb", file=sys.stderr)
        return 2
    print(f"wrote {write_text(Path(args[0]), notebook_text())}")
    return 0


if __name__ == "__main__":
    from validation.runs.environment import as_program

    as_program()  # one BLAS thread, as `tumble` has
    raise SystemExit(main())
