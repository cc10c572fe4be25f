"""A fuzzing campaign timed task by task, and where its workers' time goes.

:func:`time_campaign` runs a campaign through an executor that times every task in its worker
(:func:`timed_task`, :class:`TaskTime`); :class:`CampaignTiming` is the result: the campaign's
wall, the plants' compute (the sum of every plant run's wall, ``Outcome.walls``, over every task:
its scenes, its shrink candidates and the settling of each minimal scene; a settling task reports
no walls of its runs, so the whole task counts as the plants'), and the split of the rest
(judging, the pool's start, idle workers) with the CPU time other processes took meanwhile.
"""

from __future__ import annotations

import enum
import itertools
import multiprocessing
import os
import tempfile
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from dataclasses import dataclass
from typing import Any

from mj_bridge.plants import installed_plants
from validation.studies.fuzz.campaign import fuzz

CAMPAIGN_SCENES = 16
"""Scenes of the timed campaign: eight per worker of the pool, enough that the pool's start (a
spawned worker imports the engines) is not most of the wall, few enough to time in minutes
(``docs/performance.md``)."""
CAMPAIGN_SEED = 0


class TaskKind(enum.StrEnum):
    """What a campaign task judged."""

    SCENE = "scene"  # a plant run of a campaign scene (campaign.scene_plant_task)
    SHRINK = "shrink"  # a plant run of a shrink candidate (campaign.candidate_plant_task)
    SETTLE = "settle"  # a minimal scene at default and tightened settings (settle.settle_data)


_KINDS = {"scene_plant_task": TaskKind.SCENE, "candidate_plant_task": TaskKind.SHRINK}
"""A campaign task's function name -> its kind (any other task: :attr:`TaskKind.SETTLE`)."""


BENCH_KEY = "_bench"
"""The key :func:`timed_task` adds to a task's outcome dict (``Outcome.from_dict`` ignores it)."""


def timed_task(fn: Callable[..., dict], *args: Any) -> dict:
    """``fn(*args)`` (a campaign task, returning an outcome dict) with its own wall and process
    CPU time in the worker, s, and its start and end on the machine's monotonic clock (shared by
    every process of the machine), under :data:`BENCH_KEY`."""
    t0, c0 = time.monotonic(), time.process_time()
    out = fn(*args)
    t1, c1 = time.monotonic(), time.process_time()
    return {**out, BENCH_KEY: {"start": t0, "end": t1, "cpu_s": c1 - c0, "pid": os.getpid()}}


@dataclass(frozen=True)
class TaskTime:
    """One task of a timed campaign.

    Attributes:
        kind: scene, shrink candidate or settling.
        plants_s: the sum of its plant runs' walls (``Outcome.walls``), s; a settling task, which
            reports no walls (two runs per plant and one comparison), counts whole.
        task_s: its wall in the worker (loading the scene and forking the run included), s.
        cpu_s: the worker's CPU time during it (its plant runs' children excluded), s.
        start, end: on the machine's monotonic clock, s.
        pid: the worker's process id.
    """

    kind: TaskKind
    plants_s: float
    task_s: float
    cpu_s: float
    start: float
    end: float
    pid: int


class _Recording(Executor):
    """An executor that times every task it passes to ``inner`` (:func:`timed_task`)."""

    def __init__(self, inner: Executor) -> None:
        self.inner = inner
        self.tasks: list[TaskTime] = []

    def submit(self, fn, /, *args, **kwargs) -> Future:
        if kwargs:
            raise ValueError(f"kwargs: a campaign task takes positional arguments (got {kwargs!r})")
        kind = _KINDS.get(fn.__name__, TaskKind.SETTLE)
        f = self.inner.submit(timed_task, fn, *args)

        def note(done: Future) -> None:
            if done.cancelled() or done.exception() is not None:
                return
            res = done.result()
            b = res[BENCH_KEY]
            # a settling task reports no walls of its runs: the whole task counts as compute
            plants = sum(res["walls"].values()) if "walls" in res else b["end"] - b["start"]
            self.tasks.append(
                TaskTime(
                    kind,
                    plants,
                    b["end"] - b["start"],
                    b["cpu_s"],
                    b["start"],
                    b["end"],
                    b["pid"],
                )
            )

        f.add_done_callback(note)
        return f

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        self.inner.shutdown(wait=wait, cancel_futures=cancel_futures)


def _busy_s() -> float | None:
    """CPU seconds the whole machine has been busy (``/proc/stat``: all but idle and iowait),
    None where there is no such file."""
    try:
        with open("/proc/stat") as f:
            fields = [float(x) for x in f.readline().split()[1:]]
    except (OSError, ValueError):
        return None
    hz = os.sysconf("SC_CLK_TCK")
    return (sum(fields) - fields[3] - fields[4]) / hz


@dataclass(frozen=True)
class CampaignTiming:
    """One timed campaign.

    Attributes:
        wall_s: from the campaign's start to its end, s (the executor already made, except the
            process pool, whose start is part of what a campaign run with it waits for).
        workers: the executor's workers.
        tasks: every task, in the order they finished.
        started: the campaign's start on the machine's monotonic clock, s.
        scenes, counterexamples: what it judged and found.
        machine_busy_s: CPU time the whole machine was busy during it, s (None: unknown).
        parent_cpu_s: this process's CPU time during it, s.
    """

    wall_s: float
    workers: int
    tasks: tuple[TaskTime, ...]
    started: float
    scenes: int
    counterexamples: int
    machine_busy_s: float | None = None
    parent_cpu_s: float = 0.0

    @property
    def plants_s(self) -> float:
        """The sum of every plant run's wall over every task, s."""
        return sum(t.plants_s for t in self.tasks)

    @property
    def ratio(self) -> float:
        """Wall x workers / the plants' compute (goal 2)."""
        return self.wall_s * self.workers / self.plants_s if self.plants_s > 0 else float("inf")

    def of(self, kind: TaskKind) -> tuple[TaskTime, ...]:
        return tuple(t for t in self.tasks if t.kind is kind)

    def split(self) -> dict[str, float]:
        """Where wall x workers goes, s: ``plants`` (their runs), ``judging`` (in the workers
        beside the runs: drawing and loading the scene, forking; the comparison and the referee
        run in the campaign's own process), ``startup`` (until
        the first task started, on every worker), ``idle`` (the rest: a worker without a task,
        and moving tasks and results). ``idle`` is split by what ran meanwhile (from the tasks'
        start and end): ``idle_shrinking`` (a shrink candidate or a settling ran: the campaign
        runs those one at a time), ``idle_scenes`` (only scenes ran, fewer than the workers: the
        campaign takes results in index order with at most campaign.SCENE_WINDOW x workers
        scenes submitted, and submits no new scene while it shrinks) and ``idle_none`` (no task ran after the first:
        the parent between results)."""
        total = self.wall_s * self.workers
        plants = self.plants_s
        judging = sum(t.task_s - t.plants_s for t in self.tasks)
        first = min((t.start for t in self.tasks), default=self.started)
        startup = max(0.0, first - self.started) * self.workers
        idle = total - plants - judging - startup
        by = {"idle_shrinking": 0.0, "idle_scenes": 0.0, "idle_none": 0.0}
        end = self.started + self.wall_s
        edges = sorted({first, end, *(t.start for t in self.tasks), *(t.end for t in self.tasks)})
        for a, b in itertools.pairwise(edges):
            if b <= first or a >= end:
                continue
            running = [t for t in self.tasks if t.start < b and t.end > a]
            free = max(0, self.workers - len(running)) * (b - a)
            if not running:
                by["idle_none"] += free
            elif any(t.kind is not TaskKind.SCENE for t in running):
                by["idle_shrinking"] += free
            else:
                by["idle_scenes"] += free
        return {
            "total": total,
            "plants": plants,
            "judging": judging,
            "startup": startup,
            "idle": idle,
            **by,
        }

    @property
    def others_cpus(self) -> float | None:
        """CPUs other processes used on average during the campaign, at least: the machine's
        busy time less this process's CPU time and the tasks' (each task uses at most one CPU
        while it runs: plants are single-threaded, one BLAS thread), / the wall. None when the
        machine's busy time is unknown."""
        if self.machine_busy_s is None:
            return None
        ours = self.parent_cpu_s + sum(t.task_s for t in self.tasks)
        return max(0.0, self.machine_busy_s - ours) / self.wall_s

    def text(self) -> str:
        s = self.split()
        n_sc, n_sh = len(self.of(TaskKind.SCENE)), len(self.of(TaskKind.SHRINK))
        n_se = len(self.of(TaskKind.SETTLE))
        parts = ", ".join(
            f"{k} {s[k]:.1f} s ({s[k] / s['total']:.0%})"
            for k in ("plants", "judging", "startup", "idle")
        )
        busy = ""
        if self.others_cpus is not None:
            busy = f"; other processes used at least {self.others_cpus:.2f} CPUs meanwhile"
        longest = max(self.tasks, key=lambda t: t.task_s, default=None)
        if longest is not None:
            parts += (
                f"; the longest task ({longest.kind.value}) {longest.task_s:.1f} s, a lower bound "
                "of the wall on any number of workers"
            )
        return (
            f"wall {self.wall_s:.1f} s x {self.workers} workers = {s['total']:.1f} s: {parts}; "
            f"idle while shrinking or settling {s['idle_shrinking']:.1f} s, while only scenes "
            f"ran {s['idle_scenes']:.1f} s, with no task running {s['idle_none']:.1f} s; "
            f"{n_sc} scenes, {n_sh} shrink candidates, {n_se} settlings, "
            f"{self.counterexamples} counterexamples{busy}"
        )


def default_plants() -> tuple[str, ...]:
    """Every installed plant (a campaign's default)."""
    return tuple(str(p) for p in installed_plants())


def time_campaign(
    executor: Executor | None,
    workers_n: int,
    scenes: int = CAMPAIGN_SCENES,
    seed: int = CAMPAIGN_SEED,
    plants: Sequence[str] | None = None,
    shrink_evaluations: int | None = None,
    pool: bool = False,
) -> CampaignTiming:
    """A campaign of ``scenes`` scenes, timed (:class:`CampaignTiming`), into a temporary
    directory. ``pool``: a spawned process pool of ``workers_n`` workers is made here, inside the
    timed span (``executor`` ignored); else ``executor`` (already running) is used."""
    kw: dict[str, Any] = {"budget": scenes, "seed": seed, "report": False}
    kw["plants"] = tuple(plants) if plants is not None else default_plants()
    if shrink_evaluations is not None:
        kw["shrink_evaluations"] = shrink_evaluations
    with tempfile.TemporaryDirectory(prefix="tumble-fuzz-bench-") as tmp:
        busy0 = _busy_s()
        cpu0 = time.process_time()
        started = time.monotonic()
        t0 = time.perf_counter()
        if pool:
            inner: Executor = ProcessPoolExecutor(
                max_workers=workers_n, mp_context=multiprocessing.get_context("spawn")
            )
        else:
            assert executor is not None
            inner = executor
        rec = _Recording(inner)
        try:
            res = fuzz(tmp, executor=rec, **kw)
        finally:
            if pool:
                inner.shutdown(wait=True)
        wall = time.perf_counter() - t0
        busy1 = _busy_s()
        cpu = time.process_time() - cpu0
    busy = busy1 - busy0 if busy0 is not None and busy1 is not None else None
    return CampaignTiming(
        wall, workers_n, tuple(rec.tasks), started, len(res.scenes), len(res.counterexamples),
        busy, cpu,
    )  # fmt: skip
