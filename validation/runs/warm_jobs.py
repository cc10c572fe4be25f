"""The compile jobs of a warm-up: what each compiles, its title, and running one in this process.

A :class:`Task` is one :class:`Job` for one solve (and, for :attr:`Job.PLANT`, one plant);
:data:`KERNELS` names the jobs each plant needs. :func:`run_task` runs a task in the calling
process (a warm-up's worker, or a process that forks plant runs) and reports its wall and CPU
time, or the first line of what went wrong: a failure is never raised (the plant's own run
compiles what is missing and reports its own error), an interrupt always is. Which task runs when
is :mod:`validation.runs.warm_plan`; the warm-up itself is :mod:`validation.runs.warmup`.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING

from validation.runs import interrupts

if TYPE_CHECKING:
    from analytic.scene import Scene

ANALYTIC, MUJOCO, PINOCCHIO = "analytic", "mujoco", "pinocchio"
ENGINES = (ANALYTIC, MUJOCO, PINOCCHIO)


class Job(StrEnum):
    """One compile job of a warm-up (each runs in a worker process)."""

    SYSTEM = "system"
    """The analytic kernel's stages 1-6 (:mod:`analytic.kernel.system`), a ``cfunc``."""
    SOLVE = "solve"
    """The analytic kernel's solve for the scene's weighting (Gauss, M⁻² or identity), a ``cfunc``."""
    RHS = "rhs"
    """The analytic plant's compiled right-hand side (:mod:`analytic.compiled_rhs`)."""
    MUJOCO_STAGE = "mujoco-stage"
    """The MuJoCo plant's stage (:mod:`mj_bridge.fast_stage`) and native callback
    (:mod:`mj_bridge.native`), in that order (the callback calls the stage)."""
    PINOCCHIO_STAGE = "pinocchio-stage"
    """The Pinocchio plant's compiled stage (:mod:`mj_bridge.pinocchio_plant`)."""
    PLANT = "plant"
    """One output interval of a plant: whatever else its default settings compile."""


KERNELS: dict[str, tuple[Job, ...]] = {
    ANALYTIC: (Job.SYSTEM, Job.SOLVE, Job.RHS),
    MUJOCO: (Job.SYSTEM, Job.SOLVE, Job.MUJOCO_STAGE),
    PINOCCHIO: (Job.SYSTEM, Job.SOLVE, Job.PINOCCHIO_STAGE),
}
"""The kernels each plant needs (every plant embeds the analytic kernel's two halves)."""

TITLES: dict[Job, str] = {
    Job.SYSTEM: "analytic kernel, stages 1-6 (analytic.kernel.system)",
    Job.SOLVE: "analytic kernel, {solve} solve (analytic.kernel)",
    Job.RHS: "analytic plant's right-hand side, {solve} (analytic.compiled_rhs)",
    Job.MUJOCO_STAGE: "MuJoCo plant's stage and native callback, {solve} (mj_bridge.native)",
    Job.PINOCCHIO_STAGE: "Pinocchio plant's stage, {solve} (mj_bridge.pinocchio_plant)",
    Job.PLANT: "{engine} plant, one output interval of {scene}",
}


@dataclass(frozen=True)
class Task:
    """One job for one solve (and, for :attr:`Job.PLANT`, one plant).

    Attributes:
        job: what is compiled.
        solver: the solve it embeds (an :class:`analytic.kernel.entry.Solver` value; ignored by
            :attr:`Job.SYSTEM`, which is the same for every weighting).
        scene: a scene of that solve (the kernels' machine code does not depend on which).
        engine: the plant of a :attr:`Job.PLANT` (else "").
    """

    job: Job
    solver: int
    scene: Scene
    engine: str = ""

    @property
    def key(self) -> tuple:
        """What makes two tasks the same compile: the job, its solve and its plant."""
        return (self.job, None if self.job is Job.SYSTEM else self.solver, self.engine)

    @property
    def title(self) -> str:
        # deferred: analytic, mj_bridge: numpy ~45 ms, numba ~0.2 s (-X importtime); a warm start needs neither
        from analytic.kernel.entry import Solver

        solve = {int(Solver.MINV2): "M⁻²", int(Solver.IDENTITY): "identity"}.get(
            self.solver, "Gauss"
        )
        return TITLES[self.job].format(solve=solve, engine=self.engine, scene=self.scene.name)


@dataclass(frozen=True)
class StageTime:
    """One job done: its title, wall and CPU time in its worker (s), and its error ("" when it
    worked)."""

    title: str
    seconds: float
    error: str = ""
    cpu_seconds: float = 0.0


def run_task(task: Task) -> StageTime:
    """Compile ``task`` in this process (or load it from numba's cache); its wall time, or the
    first line of what went wrong."""
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        _COMPILE[task.job](task)
        error = ""
    except KeyboardInterrupt:
        raise
    except Exception as exc:  # the plant's own run will compile and report
        interrupts.raise_if_interrupt(exc)  # not a failure a signal caused
        error = f"{type(exc).__name__}: {exc}".splitlines()[0]
    return StageTime(task.title, time.perf_counter() - t0, error, time.process_time() - c0)


def _compile_half(task: Task) -> None:
    from analytic.kernel import halves
    from analytic.kernel.entry import Solver

    halves.compiled(halves.KernelHalf(task.job.value), Solver(task.solver))


def _compile_rhs(task: Task) -> None:
    from analytic import compiled_stepping

    if not compiled_stepping.prepare(task.solver):
        raise RuntimeError(compiled_stepping.unavailable())


def _compile_mujoco_stage(task: Task) -> None:
    from analytic.kernel.entry import Solver
    from mj_bridge import fast_stage, native

    fast_stage.compile_for(Solver(task.solver))
    if native.available():
        native.compiled(Solver(task.solver))


def _compile_pinocchio_stage(task: Task) -> None:
    from analytic.runtime import compile_lock
    from mj_bridge import pinocchio_plant as pp

    with compile_lock.compiling(compile_lock.PINOCCHIO):  # as the plant's own run takes it
        pp.PinocchioDynamics(task.scene, pp.PinocchioSettings().controller).compile()


def _compile_plant(task: Task) -> None:
    """One output interval, its warnings silenced: it runs only to compile; what the scene's
    physics says (an unstable run's overflows, MuJoCo's warnings) the run itself reports."""
    from mj_bridge.plants import plant

    pl = plant(task.engine)
    scene = task.scene
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pl.simulate(scene, pl.default_settings(scene), t_end=1.0 / scene.output.rate)


_COMPILE: dict[Job, Callable[[Task], None]] = {
    Job.SYSTEM: _compile_half,
    Job.SOLVE: _compile_half,
    Job.RHS: _compile_rhs,
    Job.MUJOCO_STAGE: _compile_mujoco_stage,
    Job.PINOCCHIO_STAGE: _compile_pinocchio_stage,
    Job.PLANT: _compile_plant,
}
