"""The executor of one job's stages: its plants, then the helpers that make its evidence, in
worker processes side by side or here one after the other, with the same results.

A job (:mod:`validation.validate`: ``tumble validate``, ``tumble judge``) says what each stage
is; a :class:`StagePool` says where and how it runs, and is the job's one face onto forking,
priorities, signal holds, time limits and the redoing of a lost worker:

* ``StagePool(concurrent, helpers, prepare_here)``: the stages fork (:mod:`validation.runs.workers`)
  when ``concurrent`` and :func:`validation.runs.workers.can_fork`, else run here; used as a
  context manager, leaving it ends every helper still running (after an error or an interrupt
  too).
* :meth:`StagePool.run_plants`: every plant's run (:func:`validation.runs.plant_runs.run_plants`:
  each with its scene copy, its time limit, its result checked; a built-in plant's lost worker
  redone here), returned as :class:`~validation.runs.plant_runs.PlantResults`. As soon as every
  plant has started, ``prepare_here()`` runs here (forking only) with the signals held (an
  interrupt tells the plants at once and is raised once it is done), and then each
  :class:`Helper` starts: a worker preparing (its imports) at idle priority
  (:mod:`validation.runs.priority`), so the plants keep the CPUs.
* :meth:`StagePool.run_helpers`: each helper given its inputs and its result collected; a helper
  whose worker was lost is redone here (said in ``redone``); an interrupt while they work raises
  ``KeyboardInterrupt``; a file a helper could not write raises
  :class:`~validation.runs.atomic.OutputError`; any other error of a helper is its result.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from analytic.scene import Scene
from validation.runs import workers
from validation.runs.atomic import OutputError
from validation.runs.interrupts import signals_held
from validation.runs.plant_runs import PlantResults, PlantRun, Progress, run_plants


@dataclass(frozen=True)
class Helper:
    """A stage after the plants, started while they run and given its inputs once they exist.

    Attributes:
        name: what the stage is (for messages).
        task: ``task(*inputs, report=...)``, its result picklable.
        prepare: run in its worker at once, at idle priority (imports), before the inputs come.
    """

    name: str
    task: Callable[..., Any]
    prepare: Callable[[], None] | None = None


@dataclass(frozen=True)
class HelperResults:
    """What :meth:`StagePool.run_helpers` got: each helper's result, in the helpers' order (an
    ``Exception``: the error the helper raised), and one line for each helper redone here."""

    results: tuple[Any, ...]
    redone: tuple[str, ...] = ()


class StagePool:
    """Where one job's stages run (module docstring)."""

    def __init__(
        self,
        concurrent: bool,
        helpers: Sequence[Helper] = (),
        prepare_here: Callable[[], None] | None = None,
    ):
        self.fork = concurrent and workers.can_fork()
        self._helpers = tuple(helpers)
        self._prepare_here = prepare_here
        self._jobs: list[workers.Job] = []

    def __enter__(self) -> StagePool:
        return self

    def __exit__(self, *exc: object) -> None:
        workers.stop(self._jobs)

    def run_plants(
        self,
        runs: Sequence[PlantRun],
        scene: Scene,
        horizon: float,
        progress: Progress | None,
        task: Callable[..., tuple[Any, float]] | None = None,
    ) -> PlantResults:
        """Every plant's run (module docstring); ``task`` as
        :func:`validation.runs.plant_runs.run_plants`'."""
        return run_plants(
            runs, scene, horizon, progress, self.fork, on_started=self._start_helpers, task=task
        )

    def _start_helpers(self, plant_jobs: Sequence[workers.Job] = ()) -> None:
        if self.fork and self._prepare_here is not None:
            with signals_held(on_signal=lambda: workers.interrupt(plant_jobs)):
                self._prepare_here()
        self._jobs[:] = [
            workers.start(
                h.name,
                h.task,
                prepare=h.prepare,
                later=True,
                idle_until_given=True,  # the plants keep the CPUs
                fork=self.fork,
            )
            for h in self._helpers
        ]

    def run_helpers(
        self, inputs: Sequence[tuple], order: Sequence[int] | None = None
    ) -> HelperResults:
        """Helper ``k`` given ``inputs[k]`` (in ``order``: a helper still importing is given its
        inputs last, as a pipe blocks until its reader reads), and every result collected
        (module docstring). The helpers start here if the plants did not start them."""
        if not self._jobs:
            self._start_helpers()
        for k in order if order is not None else range(len(self._jobs)):
            self._jobs[k].give(*inputs[k])
        if workers.wait(self._jobs):  # an interrupt while the helpers work stops the job
            raise KeyboardInterrupt
        results: list[Any] = []
        redone: list[str] = []
        for job, helper, args in zip(self._jobs, self._helpers, inputs, strict=True):
            try:
                results.append(
                    _result(job, lambda h=helper, a=args: h.task(*a, report=None), redone)
                )
            except OutputError:
                raise
            except Exception as exc:  # the helper's bug: its result
                results.append(exc)
        return HelperResults(tuple(results), tuple(redone))


def _result(job: workers.Job, redo: Callable[[], Any], redone: list[str]) -> Any:
    """A helper's result; when its worker was lost, ``redo()`` does it here (said in ``redone``).
    An interrupt goes on; the helper's own error is a ``RuntimeError`` naming it."""
    try:
        return job.result()
    except workers.WorkerLost as exc:
        if job.interrupted:
            raise KeyboardInterrupt(str(exc)) from None
        redone.append(f"{exc}; made again in the main process")
        return redo()
    except workers.WorkerError as exc:
        raise RuntimeError(str(exc)) from None


__all__ = ["Helper", "HelperResults", "StagePool"]
