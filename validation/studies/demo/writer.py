"""``tumble demo`` (:func:`write_demo`): the steps run, ``demo.rrd`` (one tab per step), each step's
figure and ``demo.md`` written into one output directory, swapped in whole."""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from pathlib import Path

from validation.compare.checks import Comparison
from validation.recording.recording import AppId, atomic_stream, narrative_for
from validation.runs.atomic import write_text
from validation.runs.outputs import OutputRun, output_run
from validation.studies.demo.figure import write_step_figures
from validation.studies.demo.guide import demo_markdown
from validation.studies.demo.recording import log_step, step_layout
from validation.studies.demo.runs import DEMO_RTOL, DEMO_T_END, run_steps
from validation.studies.demo.step import DemoStep


@dataclass(frozen=True)
class DemoResult:
    """What :func:`write_demo` wrote: ``rrd`` and ``markdown`` paths, the steps, wall times (s).

    ``os.fspath(result)`` is the output directory, so ``Path(result) / "demo.rrd"`` works.
    """

    out_dir: Path
    rrd: Path
    markdown: Path
    steps: tuple[DemoStep, ...]
    wall_times: dict[str, float]
    comparisons: tuple[Comparison, ...] = ()
    """Per step, the analytic plant against the MuJoCo ghost (empty without MuJoCo)."""
    figures: tuple[Path, ...] = ()
    """Per step, its figure (``{prefix}.png``): the tab's plots, for reading without a viewer."""

    def __fspath__(self) -> str:
        return str(self.out_dir)


def write_demo(
    out_dir: str | Path,
    *,
    t_end: float = DEMO_T_END,
    rtol: float = DEMO_RTOL,
    mujoco: bool = True,
) -> DemoResult:
    """Write the teaching demo into ``out_dir``: ``demo.rrd`` (one tab per step) and ``demo.md``.

    Each step runs on the analytic plant for ``t_end`` seconds at ``rtol`` (DOP853) and, with
    ``mujoco`` (and the MuJoCo twin importable), on the MuJoCo twin under the same controller (the
    scene's integrator and timestep), drawn as a translucent ghost over the analytic body with its
    curves in the same plots.
    """
    with output_run(out_dir, "demo") as run:
        res = _demo_into(run, t_end, rtol, mujoco)
    return dataclasses.replace(
        res,
        out_dir=run.target,
        rrd=run.final(res.rrd.name),
        markdown=run.final(res.markdown.name),
        figures=tuple(run.final(f.name) for f in res.figures),
    )


def _demo_into(run: OutputRun, t_end: float, rtol: float, mujoco: bool) -> DemoResult:
    """:func:`write_demo`'s work, writing into the staging directory ``run.path``."""
    import rerun.blueprint as rrb

    out = run.path
    runs, walls = run_steps(t_end, rtol, mujoco)
    two = all(r.two_plants for r in runs)

    path = out / "demo.rrd"
    t0 = time.perf_counter()
    tabs = [step_layout(r.step, r.scene, two, r.comparison, r.plants) for r in runs]
    bp = rrb.Blueprint(rrb.Tabs(*tabs), rrb.TimePanel(state="expanded"))
    with atomic_stream(path, AppId.DEMO, blueprint=bp, recording_id=run.run_id) as rec:
        for r in runs:
            log_step(rec, r)
    walls["recording"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    figures = write_step_figures(out, runs)
    walls["figures"] = time.perf_counter() - t0
    mdp = write_text(
        out / "demo.md",
        demo_markdown(
            [(r.step, r.scene, r.plants[0]) for r in runs],
            t_end,
            rtol,
            two,
            shown=run.final(path.name),
            bodies=[
                narrative_for(r.scene, list(r.plants), r.comparison, r.step.narrative, None)
                for r in runs
            ],
            figures=[f.name for f in figures],
        ),
    )
    return DemoResult(
        out,
        path,
        mdp,
        tuple(r.step for r in runs),
        walls,
        tuple(r.comparison for r in runs) if two else (),
        figures,
    )


__all__ = ["DemoResult", "write_demo"]
