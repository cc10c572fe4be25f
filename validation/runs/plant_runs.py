"""Every plant's run of one job: side by side in worker processes or here, each with its own copy
of the scene, its wall-time limit, and its result checked before anyone compares it.

:func:`run_plants` is the plant stage of ``tumble validate`` and ``tumble judge``
(:mod:`validation.validate`). A plant is not trusted with anything but its own run:

* it is given a read-only copy of the scene of its own (:func:`validation.runs.contract.plant_scene`);
* its run has a wall-time limit (:func:`plant_time_limit`: the caller's, else
  :data:`PLUGIN_TIME_LIMIT_S` for a plugin and none for a built-in), enforced by the workers
  (:mod:`validation.runs.workers`: a worker past it is ended; a run made here is stopped by a timer);
* what it returns is kept only when it keeps the plant contract
  (:func:`validation.runs.contract.contract_problem`);
* a worker that exits, crashes or is killed, a run that raises anything (``SystemExit`` too), over
  time or breaking the contract, fails that plant alone, in one line naming it. Only a built-in
  plant whose worker was killed from outside (``kill -9``) is run again here (and said so); a
  plugin's lost worker never is: run here, its crash would be this process's.
"""

from __future__ import annotations

import contextlib
import inspect
import math
import signal
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from analytic.scene import Scene
from analytic.trajectory import RunStatus, Trajectory
from mj_bridge.registry import BUILTIN
from validation.runs import workers
from validation.runs.atomic import OutputError
from validation.runs.contract import contract_problem, plant_scene
from validation.runs.interrupts import raise_pending
from validation.runs.time_limit import OverTime

Progress = Callable[[str, float], None] | Callable[[float], None]
"""``progress(stage, t)`` (stage a plant's name) or ``progress(t)``: t is the simulated time
reached, s. A one-argument callable is told the analytic plant's progress only."""


def _one_line(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}".splitlines()[0]


PLUGIN_TIME_LIMIT_S = 600.0
"""A plugin plant's wall-time limit per run when none is given (``--time-limit``), s: a plugin
whose run never returns is stopped. Ten minutes bounds a hang without cutting short an engine that
is honestly slow on a long horizon (give ``--time-limit`` for more); the built-in plants have no
limit unless one is given."""


def plant_time_limit(engine: str, time_limit: float | None = None) -> float | None:
    """The wall-time limit of plant ``engine``'s run, s: ``time_limit`` when given, else
    :data:`PLUGIN_TIME_LIMIT_S` for a plugin and None (no limit) for a built-in."""
    if time_limit is not None:
        return float(time_limit)
    return None if engine in BUILTIN else PLUGIN_TIME_LIMIT_S


def check_time_limit(value: Any) -> float | None:
    """``value`` as a time limit in s (None stays None), or ``ValueError`` naming ``time_limit``."""
    if value is None:
        return None
    ok = isinstance(value, int | float) and not isinstance(value, bool)
    if not (ok and math.isfinite(value) and value > 0):
        raise ValueError(f"time_limit: must be a positive finite time in s (got {value!r})")
    return float(value)


def stage_progress(progress: Any, stage: str) -> Callable[[float], None] | None:
    """Adapt either form of ``progress`` to the engines' ``progress(t)``."""
    if progress is None:
        return None
    try:
        params = inspect.signature(progress).parameters.values()
        two = sum(
            p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) for p in params
        ) >= 2 or any(p.kind is p.VAR_POSITIONAL for p in params)
    except (TypeError, ValueError):
        two = False
    if two:
        return lambda t: progress(stage, t)
    return progress if stage == "analytic" else None


def _throttled(
    report: Callable[[float], None],
    horizon: float,
    every_s: float = 0.1,
    watch: Callable[[float, Any], None] | None = None,
):
    """``progress(t)`` passing at most one ``t`` per ``every_s`` seconds on, and the last one;
    every call is a point where an interrupt compiled code swallowed is raised again (a plant in
    a worker process compiles or loads its kernels there). With ``watch``, ``progress(t, q=None)``
    that also hands every state the plant gives to ``watch(t, q)`` (unthrottled: the watcher
    keeps what it wants; ``report`` never sees a state)."""
    last = [-math.inf]

    def progress(t: float) -> None:
        raise_pending()
        now = time.monotonic()
        if now - last[0] >= every_s or t >= horizon:
            last[0] = now
            report(t)

    if watch is None:
        return progress  # a plant computes no state for it (analytic.progress.takes_state)

    def watched(t: float, q: Any = None) -> None:
        if q is not None:
            watch(t, q)
        progress(t)

    return watched


def plant_task(
    pl: Any, settings: Any, sc: Scene, horizon: float, *, report, watch=None
) -> tuple[Any, float]:
    """One plant's run (in a worker or here): its trajectory and its own wall time, s. ``report``
    is told the simulated time reached (a few times a second); ``watch(t, q)``, when given, every
    state the plant passes its progress (:mod:`analytic.progress`)."""
    t0 = time.perf_counter()
    progress = _throttled(report, horizon, watch=watch)
    tr = pl.simulate(sc, settings, t_end=horizon, progress=progress)
    return tr, time.perf_counter() - t0


@dataclass(frozen=True)
class PlantRun:
    """One plant of a job: the plant, its settings and its run's wall-time limit, s (None: none)."""

    plant: Any
    settings: Any
    limit_s: float | None = None


@dataclass(frozen=True)
class PlantResults:
    """What :func:`run_plants` got.

    Attributes:
        trajectories: the runs kept, in the order of the plants given (a plant that failed has
            none).
        walls: plant -> its run's own wall time, s (the plants kept).
        failures: one line for each plant that failed, naming it.
        redone: one line for each plant whose worker was lost and which was run again here.
        interrupted: a Ctrl-C or SIGTERM stopped the plants (each kept what it reached).
    """

    trajectories: tuple[Trajectory, ...] = ()
    walls: Mapping[str, float] = field(default_factory=dict)
    failures: tuple[str, ...] = ()
    redone: tuple[str, ...] = ()
    interrupted: bool = False


def run_plants(
    runs: Sequence[PlantRun],
    sc: Scene,
    horizon: float,
    progress: Progress | None,
    fork: bool,
    on_started: Callable[[Sequence[workers.Job]], None] | None = None,
    task: Callable[..., tuple[Any, float]] | None = None,
) -> PlantResults:
    """Every plant's run, side by side in workers where ``fork`` (no more at a time than there are
    CPUs), else one after the other here; a plant whose worker was lost is redone here (said in
    ``redone``). ``on_started(jobs)`` runs once, here, as soon as every plant has started
    (``jobs``: those running in workers). ``task``: what runs one plant,
    ``task(plant, settings, scene, horizon, report=...) -> (trajectory, wall)`` (None:
    :func:`plant_task`).

    Each plant is given a scene of its own (:func:`validation.runs.contract.plant_scene`), and what
    it returns is kept only when it keeps the plant contract (:func:`_plant_outcome`).

    An interrupt (Ctrl-C, SIGTERM) stops every plant at once (the workers are told,
    :func:`validation.runs.workers.wait`), starts no further one, and keeps what each reached."""
    task = task or plant_task
    walls: dict[str, float] = {}
    failures: list[str] = []
    redone: list[str] = []
    slots = workers.available_cpus() if fork else 1
    queue = list(enumerate(runs))
    running: list[tuple[int, PlantRun, workers.Job]] = []
    done: dict[int, Trajectory] = {}
    reached: dict[str, float] = {}
    interrupted = False
    try:
        while queue or running:
            while queue and len(running) < slots and not interrupted:
                k, run = queue.pop(0)
                name = run.plant.engine
                report = _reaching(stage_progress(progress, name), reached, name)
                job = workers.start(
                    name,
                    task,
                    run.plant,
                    run.settings,
                    plant_scene(sc),
                    horizon,
                    on_message=report,
                    fork=fork,
                    time_limit_s=run.limit_s,
                )
                running.append((k, run, job))
            if on_started is not None and not queue:  # every plant has started
                on_started, then = None, on_started
                try:
                    then([job for *_, job in running if job.forked])
                except KeyboardInterrupt:  # the plants were told: collect what they reached
                    interrupted = True
            if interrupted:  # an interrupt stops the run, it does not start the next plant
                failures += [f"{r.plant.label} plant: not run (interrupted)" for _, r in queue]
                queue = []
            if all(job.forked for *_, job in running):
                jobs = [job for *_, job in running]
                interrupted |= workers.wait(jobs, first=not interrupted, interrupted=interrupted)
                finished = [r for r in running if r[2].done]
            else:  # a plant that runs here
                finished = [next(r for r in running if not r[2].forked)]
            for k, run, job in finished:
                running.remove((k, run, job))
                pl = run.plant
                redo = _redo_plant(task, pl, run.settings, sc, horizon, progress)
                tr = _plant_outcome(
                    pl, job, walls, failures, redo, redone, (sc, horizon, reached.get(pl.engine))
                )
                interrupted |= job.interrupted
                if tr is None:
                    continue
                done[k] = tr
                interrupted |= tr.status is RunStatus.INTERRUPTED
                if tr.status is not RunStatus.OK:
                    failures.append(f"{pl.engine} plant stopped early: {tr.message}")
    except BaseException:
        workers.stop([job for *_, job in running])
        raise
    return PlantResults(
        tuple(done[k] for k in sorted(done)), walls, tuple(failures), tuple(redone), interrupted
    )


def _redo_plant(
    task: Callable[..., tuple[Any, float]],
    pl: Any,
    settings: Any,
    sc: Scene,
    horizon: float,
    progress: Progress | None,
) -> Callable[[], tuple[Any, float]]:
    """The plant's run done here (its worker was lost): ``() -> (trajectory, wall)``."""
    report = stage_progress(progress, pl.engine) or _drop
    return lambda: task(pl, settings, plant_scene(sc), horizon, report=report)


def _drop(_msg: Any) -> None:
    pass


def _reaching(
    report: Callable[[float], None] | None, reached: dict[str, float], name: str
) -> Callable[[Any], None]:
    """``report`` (None: nothing) that also keeps in ``reached[name]`` the last simulated time the
    plant reported (what a run stopped at its time limit had reached)."""

    def heard(t: Any) -> None:
        if isinstance(t, int | float):
            reached[name] = float(t)
        if report is not None:
            report(t)

    return heard


def _plant_outcome(
    pl: Any,
    job: workers.Job,
    walls: dict[str, float],
    failures: list[str],
    redo: Callable[[], tuple[Any, float]],
    redone: list[str],
    run: tuple[Scene, float, float | None],
) -> Trajectory | None:
    """The plant's trajectory (its wall time into ``walls``), or None with the failure said in
    one line naming the plant. ``run``: the scene, the horizon (s) and the simulated time the
    plant last reported (s; None: none).

    A built-in plant whose worker was killed from outside (``kill -9``; not by an interrupt) is
    run again here, and ``redone`` says so. A plugin's lost worker, and any worker that ended by
    its own doing (an exit, a crash signal), fails that plant: run here, its crash would be this
    process's. A run over its time limit fails that plant, naming the limit; so does one that
    raises anything (``SystemExit`` of a run made here too) or returns what breaks the plant
    contract (:func:`validation.runs.contract.contract_problem`)."""
    sc, horizon, reached = run
    try:
        try:
            tr, wall = job.result()
        except workers.WorkerLost as exc:
            if job.interrupted:
                raise KeyboardInterrupt(str(exc)) from None
            if not (exc.killed and pl.engine in BUILTIN):
                own = "" if exc.killed else ", by its own doing"
                failures.append(
                    f"{pl.label} plant: {_lost_sentence(exc)}{own} (not run again here)"
                )
                return None
            redone.append(f"{pl.label} plant: {exc}; run again in the main process")
            tr, wall = redo()
    except OutputError:
        raise  # a file that could not be written: no verdict
    except OverTime as exc:
        at = f" at t = {reached:.6g} s" if reached is not None else ""
        failures.append(f"{pl.label} plant: stopped at its time limit of {exc.limit_s:g} s{at}")
        return None
    except workers.WorkerError as exc:
        # Bad input was refused before any plant started (run_validation's checks): whatever a
        # plant raises now, a ValueError from deep in an engine included, is that plant failing,
        # and the run keeps what it has, marked failed.
        failures.append(f"{pl.label} plant: {exc}")
        return None
    except KeyboardInterrupt:
        job.interrupted = True
        failures.append(f"{pl.label} plant: not run (interrupted)")
        return None
    except Exception as exc:
        failures.append(f"{pl.label} plant: {_one_line(exc)}")
        return None
    except BaseException as exc:  # SystemExit, GeneratorExit ... of a plant run here
        failures.append(f"{pl.label} plant: {_one_line(exc)}")
        return None
    problem = contract_problem(tr, pl.engine, sc, horizon)
    if problem:
        failures.append(f"{pl.label} plant: broke the plant contract: {problem}")
        return None
    walls[pl.engine] = wall
    return tr


def _lost_sentence(exc: workers.WorkerLost) -> str:
    """``its worker process ended (exit -11, SIGSEGV) without a result``."""
    code = exc.exitcode
    why = f"exit {code}"
    if code is not None and code < 0:
        with contextlib.suppress(ValueError):
            why += f", {signal.Signals(-code).name}"
    return f"its worker process ended ({why}) without a result"


__all__ = [
    "PLUGIN_TIME_LIMIT_S",
    "PlantResults",
    "PlantRun",
    "Progress",
    "check_time_limit",
    "plant_task",
    "plant_time_limit",
    "run_plants",
    "stage_progress",
]
