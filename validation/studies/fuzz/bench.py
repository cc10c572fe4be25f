"""The campaign's throughput goals, measured in one process.

1. **Scene-validations per core-minute.** One validation is what a campaign does per scene: every
   plant's run at the scene's default settings, :func:`validation.compare.compare_plants` and the
   referee, no figure, recording or file (:func:`validation.studies.fuzz.judge.judge_scene`).
   Measured on the controlled Example 1 over a 2 s horizon with the three plants (the goal: at
   least :data:`GOAL_PER_CORE_MINUTE`), by CPU time (this thread's and that of the child processes
   the plant runs are made in), so the figure is per core whatever else the machine runs; the
   plants' own share (their wall times) is reported beside it.
2. **A campaign's wall against its plants' compute** (:func:`goal_campaign_wall`): a campaign of
   :data:`CAMPAIGN_SCENES` random scenes (seed :data:`CAMPAIGN_SEED`, the default horizon, every
   installed plant) on a local process pool of :data:`CAMPAIGN_WORKERS` workers. Ratio = the
   campaign's wall x the workers / the sum of every plant run's wall (``Outcome.walls``) over
   every task the campaign ran: its scenes *and* its shrink candidates and the settling of each
   minimal scene (part of what a campaign costs: a campaign that finds something spends most of
   its plant runs shrinking it; a settling task reports no walls of its runs, so the whole task
   counts as the plants').
   Holds when ≤ :data:`CAMPAIGN_WALL_LIMIT`. A plant run's wall is measured around the run in the
   worker (:func:`validation.studies.fuzz.judge.run_limited`), so it includes starting and reaping
   the run's child process; everything else (the pool's start, drawing and loading scenes, the
   comparison, the referee, sending results back, writing scene files, shrinking's waits, idle
   workers) is the overhead the goal bounds. :class:`CampaignTiming` splits it.
3. **Two Dask workers against one** (:func:`goal_dask_scaling`): the same campaign on a Dask
   ``LocalCluster`` of one worker process, then of two (``tumble fuzz --dask-workers N``), each
   timed from the campaign's start to its end with the cluster already up (a cluster's start is
   the same whatever the campaign). Ratio = wall with two / wall with one; holds when ≤
   :data:`DASK_RATIO_LIMIT` (two workers at least :data:`DASK_SPEEDUP_GOAL` times as fast).

Goals 2 and 3 are single campaign runs (no rounds, so no spread: a verdict is the value's; the
machine's other load changes them, and the CPU time other processes took during the run is
printed beside them). They take minutes, so they run only when asked:
``python -m validation.studies.fuzz.bench [ROUNDS] [--campaign]``.

Beside them, :func:`served_overhead` measures what the hard time limit costs per plant run: a run
forked from this process (single-threaded) against one forked by the fork server (what a
multi-threaded process, a Dask worker, uses), against the same run made here.
"""

from __future__ import annotations

import enum
import itertools
import multiprocessing
import os
import resource
import statistics
import tempfile
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor, ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

from analytic.scene import Scene, scene_from_dict
from analytic.scene.dump import scene_to_dict
from mj_bridge.plants import installed_plants, plant
from validation.bench.goals import Goal
from validation.bench.verdicts import Verdict
from validation.runs import workers
from validation.scenes import resolve_scene
from validation.studies.fuzz.campaign import fuzz
from validation.studies.fuzz.judge import _simulate_task, judge_scene, run_limited
from validation.studies.sweep.running import executor_for

GOAL_PER_CORE_MINUTE = 200.0
"""Scene-validations per core-minute the campaign is meant to reach on Example 1 (2 s, three
plants)."""
SCENE = "paper_example1_controlled"
HORIZON_S = 2.0

CAMPAIGN_SCENES = 16
"""Scenes of the timed campaign: eight per worker of the pool, enough that the pool's start (a
spawned worker imports the engines, about 2 s) is not most of the wall, few enough to time in
about two minutes on the 2-core machine."""
CAMPAIGN_SEED = 0
"""The timed campaign's seed: its scenes, findings and shrinks are the same on every run."""
CAMPAIGN_WORKERS = 2
"""Workers of the timed process pool: the 2-core development machine's cores."""
CAMPAIGN_WALL_LIMIT = 1.3
"""Campaign wall x workers / the plants' compute, at most: what is not a plant run (the
comparison and referee of each scene, about a tenth of its runs' time on Example 1; drawing and
loading scenes; files; the pool's start) may add 30 %."""
DASK_SPEEDUP_GOAL = 1.7
"""Two Dask workers on two cores must judge the campaign at least this many times as fast as one:
85 % of the ideal 2, the rest for what cannot run side by side (the cluster's scheduling, the
parent taking results in order)."""
DASK_RATIO_LIMIT = 1.0 / DASK_SPEEDUP_GOAL
"""The Dask goal as a ``Goal`` (value ≤ limit): wall with two workers / wall with one."""


@dataclass(frozen=True)
class Throughput:
    """Median CPU time of one validation (s), the plants' share of it (their wall time, s), and
    validations per core-minute (60 / cpu_s)."""

    cpu_s: float
    plants_s: float
    per_core_minute: float
    rounds: int


def _children_cpu_s() -> float:
    """CPU time of this process's children that have ended and been reaped, s."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _reap_children() -> None:
    """Wait for this process's child processes to end (a plant run's child exits on its own
    just after sending its run), so their CPU time is counted now."""
    for child in multiprocessing.active_children():
        child.join()


def measure(
    rounds: int = 5, plants: tuple[str, ...] = ("analytic", "mujoco", "pinocchio")
) -> Throughput:
    """:class:`Throughput` over ``rounds`` validations (after one unmeasured, which loads the
    compiled kernels). A validation's CPU time is this thread's plus that of the child processes
    its plant runs were made in (:func:`validation.studies.fuzz.judge.run_limited` forks one per
    run where it can): the children are reaped after each validation and their CPU time added."""

    data = scene_to_dict(resolve_scene(SCENE))
    data["output"]["t_end"] = HORIZON_S
    judge_scene(data, plants, HORIZON_S)
    _reap_children()
    cpu, comp = [], []
    for _ in range(rounds):
        k0 = _children_cpu_s()
        c0 = time.thread_time()
        out = judge_scene(data, plants, HORIZON_S)
        c1 = time.thread_time()
        _reap_children()
        cpu.append(c1 - c0 + _children_cpu_s() - k0)
        comp.append(sum(out.walls.values()))
    c = statistics.median(cpu)
    return Throughput(c, statistics.median(comp), 60.0 / c, rounds)


# ------------------------------------------------------------------------------------------------
# A campaign, timed task by task
# ------------------------------------------------------------------------------------------------


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


OTHERS_BOUND_CPUS = 0.1
"""The most CPU other processes may have used during a timed campaign (on average, CPUs) for its
goal to get a verdict; above it the verdict is TOO_BUSY. A campaign's workers fill the cores, so
work of another process takes a core from them: a tenth of a CPU changes a two-worker wall by at
most about 5 %, against the goals' margins (1.3 against 1.0-1.1 measured alone on one worker; 1.7
against 2)."""


def campaign_verdict(goal: Goal, others_cpus: float | None) -> Verdict:
    """``goal``'s verdict, or TOO_BUSY when other processes used more than
    :data:`OTHERS_BOUND_CPUS` during its campaign(s) (unknown: the goal's own verdict)."""
    if goal.skipped or others_cpus is None or others_cpus <= OTHERS_BOUND_CPUS:
        return goal.verdict
    return Verdict.TOO_BUSY


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


CAMPAIGN_GOAL = (
    f"fuzz campaign ({CAMPAIGN_SCENES} random scenes, seed {CAMPAIGN_SEED}, shrinking included, "
    f"process pool of {CAMPAIGN_WORKERS}): wall x workers / the plants' compute"
)
DASK_GOAL = "fuzz campaign on Dask: wall with two workers / wall with one"


def goal_campaign_wall(
    scenes: int = CAMPAIGN_SCENES, progress: Callable[[str], None] = print
) -> Goal:
    """Goal 2 (module docstring). ``data``: the :meth:`CampaignTiming.split` and the counts."""
    progress(f"  a campaign of {scenes} scenes on a process pool of {CAMPAIGN_WORKERS} ...")
    t = time_campaign(None, CAMPAIGN_WORKERS, scenes, pool=True)
    return Goal(
        CAMPAIGN_GOAL,
        t.ratio,
        CAMPAIGN_WALL_LIMIT,
        t.text(),
        data={
            "split_s": t.split(),
            "wall_s": t.wall_s,
            "scenes": t.scenes,
            "shrink_tasks": len(t.of(TaskKind.SHRINK)),
            "others_cpus": t.others_cpus,
        },
    )


def _most(values) -> float | None:
    """The largest of ``values``, None if any is None."""
    vs = list(values)
    return None if any(v is None for v in vs) else max(vs)


def goal_dask_scaling(
    scenes: int = CAMPAIGN_SCENES, progress: Callable[[str], None] = print
) -> Goal:
    """Goal 3 (module docstring); skipped, with the reason, when Dask is not installed. ``data``:
    each run's wall and split."""
    try:
        import distributed  # noqa: F401  # deferred: Dask is optional
    except ImportError:
        return Goal(DASK_GOAL, float("nan"), DASK_RATIO_LIMIT, skipped="Dask is not installed")
    runs: dict[int, CampaignTiming] = {}
    for n in (1, 2):
        progress(f"  the campaign on a Dask LocalCluster of {n} worker(s) ...")
        with executor_for(None, None, n) as (ex, width):
            runs[n] = time_campaign(ex, width, scenes)
        progress(f"    {runs[n].text()}")
    one, two = runs[1], runs[2]
    return Goal(
        DASK_GOAL,
        two.wall_s / one.wall_s,
        DASK_RATIO_LIMIT,
        f"one worker {one.wall_s:.1f} s, two {two.wall_s:.1f} s: {one.wall_s / two.wall_s:.2f}x "
        f"(goal ≥ {DASK_SPEEDUP_GOAL:g}x); plants' compute {one.plants_s:.1f} s / "
        f"{two.plants_s:.1f} s",
        data={
            "runs": {n: {"wall_s": r.wall_s, "split_s": r.split()} for n, r in runs.items()},
            "others_cpus": _most(r.others_cpus for r in runs.values()),
        },
    )


# ------------------------------------------------------------------------------------------------
# What the hard time limit costs per run
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class LimitOverhead:
    """Median wall of one plant run, s: made here (``here_s``), forked from this process
    (``fork_s``), forked by the fork server (``served_s``); over ``rounds`` alternating rounds
    (the first served run, which starts the server and its preload, excluded: ``server_start_s``)."""

    plant: str
    here_s: float
    fork_s: float
    served_s: float
    server_start_s: float
    rounds: int

    def text(self) -> str:
        ms = 1e3
        return (
            f"{self.plant}: run here {self.here_s * ms:.1f} ms; forked +"
            f"{(self.fork_s - self.here_s) * ms:.1f} ms; fork server +"
            f"{(self.served_s - self.here_s) * ms:.1f} ms (medians of {self.rounds}; the server's "
            f"first run, with its start and preload, {self.server_start_s:.2f} s)"
        )


def _fresh_scenes(horizon_s: float) -> Callable[[], Scene]:
    """A new scene at every call: the controlled Example 1 over ``horizon_s`` with C's initial
    velocity changed by a further 1e-6 m/s along x (the same cost; no per-scene cache of a plant
    serves it, as none serves a campaign's random scenes)."""
    data = scene_to_dict(resolve_scene(SCENE))
    data["output"]["t_end"] = horizon_s
    count = [0]

    def make() -> Scene:
        count[0] += 1
        data["initial"]["Rdot"][0] = 1.0 + 1e-6 * count[0]
        return scene_from_dict(data)

    return make


def served_overhead(
    name: str = "analytic", rounds: int = 15, horizon_s: float = 0.05
) -> LimitOverhead:
    """:class:`LimitOverhead` of plant ``name`` on the controlled Example 1 over ``horizon_s``
    (short, so the run is mostly overhead), every run on a scene not run before
    (:func:`_fresh_scenes`), as in a campaign. The fork path needs this process single-threaded
    (:func:`validation.runs.workers.can_fork`); the served runs are made from a helper thread, as
    a Dask worker's task thread makes them. ``ValueError`` naming ``name`` when forking is not
    possible here."""
    if not (workers.can_fork() and workers.can_serve()):
        raise ValueError(f"name: {name!r}: this process cannot fork (threads, or not Linux)")
    fresh = _fresh_scenes(horizon_s)
    pl = plant(name)
    limit = 60.0

    def here() -> float:
        sc = fresh()
        t0 = time.perf_counter()
        _simulate_task(pl, sc, horizon_s)
        return time.perf_counter() - t0

    def limited() -> float:
        sc = fresh()
        t0 = time.perf_counter()
        run_limited(name, pl, sc, horizon_s, limit)
        return time.perf_counter() - t0

    here()
    limited()  # loads the kernels here
    runs: dict[str, list[float]] = {"here": [], "forked": [], "served": []}
    with ThreadPoolExecutor(1) as thread:
        first = thread.submit(limited).result()
        for _ in range(rounds):
            runs["here"].append(here())
            runs["served"].append(thread.submit(limited).result())
    for _ in range(rounds):  # the thread is gone: this process may fork again
        runs["forked"].append(limited())
        runs["here"].append(here())
    med = {k: statistics.median(v) for k, v in runs.items()}
    return LimitOverhead(name, med["here"], med["forked"], med["served"], first, rounds)


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m validation.studies.fuzz.bench",
        description="The fuzzer's throughput goals, as ratios measured in this process "
        "(docs/fuzzing.md, Throughput).",
    )
    parser.add_argument(
        "rounds", nargs="?", type=int, default=5, help="timed validations (default 5)"
    )
    parser.add_argument(
        "--campaign",
        action="store_true",
        help="also the two campaign goals (wall against the plants' compute on a process pool of "
        "two; two Dask workers against one): about 8 minutes",
    )
    parser.add_argument(
        "--runaway",
        action="store_true",
        help="also the runaway campaign's goals (seed 7, 40 violent scenes over 2 s: no model "
        "finding, no run over its time limit, its wall, every counterexample reproduced by its "
        "command; validation.studies.fuzz.runaway_goal): about 4 minutes",
    )
    args = parser.parse_args(argv)
    if args.rounds < 1:
        parser.error(f"rounds: must be a whole number ≥ 1 (got {args.rounds})")
    campaign = args.campaign
    t = measure(args.rounds)
    print(
        f"one validation of {SCENE} over {HORIZON_S:g} s, three plants: CPU {t.cpu_s:.3f} s "
        f"(plants {t.plants_s:.3f} s wall), {t.per_core_minute:.0f} per core-minute "
        f"(goal ≥ {GOAL_PER_CORE_MINUTE:g}: {'holds' if t.per_core_minute >= GOAL_PER_CORE_MINUTE else 'fails'})"
    )
    if workers.can_fork() and workers.can_serve():
        for name in default_plants():
            print("hard time limit per run, " + served_overhead(name).text())
    if campaign:
        for goal in (goal_campaign_wall, goal_dask_scaling):
            g = goal()
            others = g.data.get("others_cpus")
            if campaign_verdict(g, others) is Verdict.TOO_BUSY:
                print(
                    f"{g.name}: ratio {g.value:.3g} (goal ≤ {g.limit:.3g}): the machine was too "
                    f"busy for a verdict (other processes used {others:.2f} CPUs, more than "
                    f"{OTHERS_BOUND_CPUS:g}). {g.detail}"
                )
            else:
                print(g.line())
    if args.runaway:
        from validation.studies.fuzz.runaway_goal import runaway_campaign

        for line in runaway_campaign().lines():
            print(line)
    return 0


if __name__ == "__main__":
    from validation.runs.environment import as_program

    as_program()  # one BLAS thread, as `tumble` has
    raise SystemExit(main())
