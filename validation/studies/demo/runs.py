"""The demo's runs (:func:`run_steps`): each step on the analytic plant and, when the MuJoCo twin
is importable, on MuJoCo under the same controller, compared under the report's thresholds."""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

from analytic.scene import Scene
from analytic.simulate import simulate
from analytic.trajectory import RunStatus, Trajectory
from validation.compare.checks import Comparison, compare
from validation.runs import interrupts
from validation.runs.progress import RunsProgress
from validation.scenes import resolve_scene
from validation.studies.demo.chapters import STEPS
from validation.studies.demo.step import DemoStep, step_scene

DEMO_RTOL = 1e-12  # as `tumble validate` (the scenes' rtol): the ghost is checked against it
DEMO_T_END = 10.0  # s


@dataclass(frozen=True)
class StepRun:
    """One step's runs.

    Attributes:
        step: the step.
        scene: the scene it ran (:func:`step_scene`).
        plants: the analytic run, then the MuJoCo ghost when it ran; on the output grid.
        comparison: the analytic run against the ghost (or alone), under the report's thresholds.
        baseline: for a step with an effect switched off, the analytic run of the full scene.
    """

    step: DemoStep
    scene: Scene
    plants: tuple[Trajectory, ...]
    comparison: Comparison
    baseline: Trajectory | None = None

    @property
    def two_plants(self) -> bool:
        return len(self.plants) > 1


def run_steps(
    t_end: float = DEMO_T_END,
    rtol: float = DEMO_RTOL,
    mujoco: bool = True,
    steps: Sequence[DemoStep] = STEPS,
) -> tuple[tuple[StepRun, ...], dict[str, float]]:
    """Run every step on the analytic plant (DOP853 at ``rtol``) and, with ``mujoco`` (and the
    twin importable), on MuJoCo under the same controller, and compare them; for a step with an
    effect switched off, also the full scene (an earlier step's run when there is one).

    Returns the runs, in step order, and the wall time of each run, s. A run that fails raises
    RuntimeError naming the step."""
    mj_simulate = None
    if mujoco:
        try:
            from mj_bridge import simulate as mj_simulate
        except ImportError as exc:  # pragma: no cover - the twin is part of the package
            interrupts.raise_if_interrupt(exc)  # an import a signal cut is the signal
            mj_simulate = None
    walls: dict[str, float] = {}
    runs: list[StepRun] = []
    per_step = 2 if mj_simulate is not None else 1
    total = max(1, per_step * len(steps) + _baselines(steps))
    with RunsProgress("demo", t_end, total) as shown:
        for step in steps:
            runs.append(_step_run(step, runs, t_end, rtol, mj_simulate, walls, shown))
    return tuple(runs), walls


def _baselines(steps: Sequence[DemoStep]) -> int:
    """How many full-scene runs :func:`_baseline` will make (no earlier step to take it from)."""
    n = 0
    for i, step in enumerate(steps):
        earlier = any(s.scene == step.scene and not s.switched_off for s in steps[:i])
        n += bool(step.switched_off) and not earlier
    return n


def _step_run(
    step: DemoStep,
    runs: Sequence[StepRun],
    t_end: float,
    rtol: float,
    mj_simulate,
    walls: dict[str, float],
    shown: RunsProgress,
) -> StepRun:
    """One step's runs, each reporting to ``shown`` (every report is a point where a signal
    compiled code swallowed stops the run)."""
    sc = step_scene(step)
    t0 = time.perf_counter()
    tr = simulate(sc, t_end=t_end, rtol=rtol, progress=shown.next()).raise_if_interrupted()
    walls[step.prefix] = time.perf_counter() - t0
    if tr.status is not RunStatus.OK:
        raise RuntimeError(f"demo step {step.title!r} failed: {tr.message}")
    plants = [tr]
    if mj_simulate is not None:
        t0 = time.perf_counter()
        tm = mj_simulate(sc, t_end=t_end, progress=shown.next()).raise_if_interrupted()
        walls[f"{step.prefix}_mujoco"] = time.perf_counter() - t0
        if tm.status is not RunStatus.OK:
            raise RuntimeError(f"demo step {step.title!r} failed on MuJoCo: {tm.message}")
        plants.append(tm)
    cmp = compare(tr, plants[1] if len(plants) > 1 else None, sc, t_end=t_end)
    base = _baseline(step, runs, t_end, rtol, walls, shown) if step.switched_off else None
    return StepRun(step, sc, tuple(plants), cmp, base)


def _baseline(
    step: DemoStep,
    runs: Sequence[StepRun],
    t_end: float,
    rtol: float,
    walls: dict[str, float],
    shown: RunsProgress,
) -> Trajectory:
    """The analytic run of ``step``'s scene with every effect: an earlier step's, or run now."""
    earlier = next(
        (r for r in runs if r.step.scene == step.scene and not r.step.switched_off), None
    )
    if earlier is not None:
        return earlier.plants[0]
    t0 = time.perf_counter()
    tr = simulate(resolve_scene(step.scene), t_end=t_end, rtol=rtol, progress=shown.next())
    tr = tr.raise_if_interrupted()
    walls[f"{step.prefix}_baseline"] = time.perf_counter() - t0
    if tr.status is not RunStatus.OK:
        raise RuntimeError(f"demo step {step.title!r}: the full scene failed: {tr.message}")
    return tr


__all__ = ["DEMO_RTOL", "DEMO_T_END", "StepRun", "run_steps"]
