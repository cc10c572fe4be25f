"""The campaign's wall goals: a campaign's wall against its plants' compute, and two Dask workers
against one.

* :func:`goal_campaign_wall`: a campaign of :data:`~validation.studies.fuzz.campaign_timing.CAMPAIGN_SCENES`
  random scenes (seed :data:`~validation.studies.fuzz.campaign_timing.CAMPAIGN_SEED`, the default
  horizon, every installed plant) on a local process pool of :data:`CAMPAIGN_WORKERS` workers.
  Ratio = the campaign's wall x the workers / the sum of every plant run's wall over every task the
  campaign ran (:class:`~validation.studies.fuzz.campaign_timing.CampaignTiming`). Holds when ≤
  :data:`CAMPAIGN_WALL_LIMIT`. A plant run's wall is measured around the run in the worker
  (:func:`validation.studies.fuzz.judge.run_limited`), so it includes starting and reaping the
  run's child process; everything else (the pool's start, drawing and loading scenes, the
  comparison, the referee, sending results back, writing scene files, shrinking's waits, idle
  workers) is the overhead the goal bounds.
* :func:`goal_dask_scaling`: the same campaign on a Dask ``LocalCluster`` of one worker process,
  then of two (``tumble fuzz --dask-workers N``), each timed from the campaign's start to its end
  with the cluster already up (a cluster's start is the same whatever the campaign). Ratio = wall
  with two / wall with one; holds when ≤ :data:`DASK_RATIO_LIMIT` (two workers at least
  :data:`DASK_SPEEDUP_GOAL` times as fast).

Both are single campaign runs (no rounds, so no spread: a verdict is the value's); the machine's
other load changes them, so the CPU time other processes took during the run is printed beside them
and above :data:`OTHERS_BOUND_CPUS` makes the verdict TOO_BUSY (:func:`campaign_verdict`).
"""

from __future__ import annotations

from collections.abc import Callable

from validation.bench.goal import Goal
from validation.bench.verdicts import Verdict
from validation.studies.fuzz.campaign_timing import (
    CAMPAIGN_SCENES,
    CAMPAIGN_SEED,
    CampaignTiming,
    TaskKind,
    time_campaign,
)
from validation.studies.sweep.running import executor_for

"""The timed campaign's seed: its scenes, findings and shrinks are the same on every run."""
CAMPAIGN_WORKERS = 2
"""Workers of the timed process pool: the 2-core development machine's cores."""
CAMPAIGN_WALL_LIMIT = 1.3
"""Campaign wall x workers / the plants' compute, at most: what is not a plant run (the
comparison and referee of each scene; drawing and loading scenes; files; the pool's start) may add
30 % (``docs/performance.md``)."""
DASK_SPEEDUP_GOAL = 1.7
"""Two Dask workers on two cores must judge the campaign at least this many times as fast as one:
85 % of the ideal 2, the rest for what cannot run side by side (the cluster's scheduling, the
parent taking results in order)."""
DASK_RATIO_LIMIT = 1.0 / DASK_SPEEDUP_GOAL
"""The Dask goal as a ``Goal`` (value ≤ limit): wall with two workers / wall with one."""


OTHERS_BOUND_CPUS = 0.1
"""The most CPU other processes may have used during a timed campaign (on average, CPUs) for its
goal to get a verdict; above it the verdict is TOO_BUSY. A campaign's workers fill the cores, so
work of another process takes a core from them, and a tenth of a CPU is small against the goals'
margins (``docs/performance.md``)."""


def campaign_verdict(goal: Goal, others_cpus: float | None) -> Verdict:
    """``goal``'s verdict, or TOO_BUSY when other processes used more than
    :data:`OTHERS_BOUND_CPUS` during its campaign(s) (unknown: the goal's own verdict)."""
    if goal.skipped or others_cpus is None or others_cpus <= OTHERS_BOUND_CPUS:
        return goal.verdict
    return Verdict.TOO_BUSY


CAMPAIGN_GOAL = (
    f"fuzz campaign ({CAMPAIGN_SCENES} random scenes, seed {CAMPAIGN_SEED}, shrinking included, "
    f"process pool of {CAMPAIGN_WORKERS}): wall x workers / the plants' compute"
)
DASK_GOAL = "fuzz campaign on Dask: wall with two workers / wall with one"


def goal_campaign_wall(
    scenes: int = CAMPAIGN_SCENES, progress: Callable[[str], None] = print
) -> Goal:
    """The campaign-wall goal (module docstring). ``data``: the :meth:`CampaignTiming.split` and the counts."""
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
    """The Dask goal (module docstring); skipped, with the reason, when Dask is not installed. ``data``:
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
