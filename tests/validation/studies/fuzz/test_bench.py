"""The fuzz benchmark's bookkeeping (:mod:`validation.studies.fuzz.bench`): where a timed
campaign's worker-time goes, from planted task times; the recording executor on a real (tiny)
campaign. The timings themselves are the benchmark's to print, never a test's to assert."""

from __future__ import annotations

import math

import pytest

from validation.bench.verdicts import Verdict
from validation.studies.fuzz import bench
from validation.studies.fuzz.bench import CampaignTiming, TaskKind, TaskTime
from validation.studies.fuzz.campaign import SerialExecutor


def _task(kind, plants_s, start, end):
    return TaskTime(kind, plants_s, end - start, 0.0, start, end, 1)


def test_the_split_adds_up_to_wall_times_workers():
    """Two workers over a 10 s campaign started at t = 100 s: 20 worker-seconds. The first task
    starts at 102 s (2 s of pool start on each worker: 4 s). Scenes A (102-105 s, 2.5 s of plant
    runs) and B (102-104 s, 1.5 s), then a shrink candidate (106-108 s, 1.5 s): 5.5 s of plant
    runs, 0.5 s of judging in each task. The idle 9 s: 104-105 s one worker while only A ran (1 s),
    106-108 s one worker beside the candidate (2 s), 105-106 s and 108-110 s both workers with
    nothing running (6 s)."""
    tasks = (
        _task(TaskKind.SCENE, 2.5, 102.0, 105.0),
        _task(TaskKind.SCENE, 1.5, 102.0, 104.0),
        _task(TaskKind.SHRINK, 1.5, 106.0, 108.0),
    )
    t = CampaignTiming(10.0, 2, tasks, 100.0, 2, 1, None)
    s = t.split()
    assert s["total"] == pytest.approx(20.0)
    assert s["plants"] == pytest.approx(5.5)
    assert s["judging"] == pytest.approx(1.5)
    assert s["startup"] == pytest.approx(4.0)
    assert s["idle"] == pytest.approx(9.0)
    assert s["idle_scenes"] == pytest.approx(1.0)
    assert s["idle_shrinking"] == pytest.approx(2.0)
    assert s["idle_none"] == pytest.approx(6.0)
    assert s["plants"] + s["judging"] + s["startup"] + s["idle"] == pytest.approx(s["total"])
    assert t.ratio == pytest.approx(20.0 / 5.5)
    assert "wall 10.0 s x 2 workers = 20.0 s" in t.text()


def test_other_processes_cpu_makes_a_campaign_goal_too_busy():
    """The machine busy 30 CPU-seconds over a 10 s campaign whose parent used 1 s and whose
    tasks ran 7 s in all: other processes used at least (30 - 1 - 7) / 10 = 2.2 CPUs."""
    tasks = (_task(TaskKind.SCENE, 3.0, 0.0, 4.0), _task(TaskKind.SCENE, 2.0, 0.0, 3.0))
    t = CampaignTiming(10.0, 2, tasks, 0.0, 2, 0, machine_busy_s=30.0, parent_cpu_s=1.0)
    assert t.others_cpus == pytest.approx(2.2)
    g = bench.Goal("c", 1.0, bench.CAMPAIGN_WALL_LIMIT)
    assert bench.campaign_verdict(g, t.others_cpus) is Verdict.TOO_BUSY
    assert bench.campaign_verdict(g, bench.OTHERS_BOUND_CPUS) is Verdict.HOLDS
    assert bench.campaign_verdict(g, None) is Verdict.HOLDS
    assert CampaignTiming(10.0, 2, tasks, 0.0, 2, 0).others_cpus is None


def test_a_campaign_without_plant_runs_has_no_finite_ratio():
    assert math.isinf(CampaignTiming(1.0, 2, (), 0.0, 0, 0).ratio)


def test_the_goals_read_as_ratios_at_most_their_limits():
    """Two Dask workers 1.7 times as fast as one is a wall ratio of 1/1.7; a campaign exactly at
    1.3 x its plants' compute holds, just above it fails."""
    assert bench.DASK_RATIO_LIMIT == pytest.approx(1 / bench.DASK_SPEEDUP_GOAL)
    assert bench.Goal("c", 1.3, bench.CAMPAIGN_WALL_LIMIT).verdict is Verdict.HOLDS
    assert bench.Goal("c", 1.31, bench.CAMPAIGN_WALL_LIMIT).verdict is Verdict.FAILS


def test_timed_task_keeps_the_outcome_and_adds_its_times():
    out = bench.timed_task(lambda a, b: {"walls": {"x": a}, "ran": [b]}, 0.25, "x")
    assert out["walls"] == {"x": 0.25} and out["ran"] == ["x"]
    b = out[bench.BENCH_KEY]
    assert b["end"] >= b["start"] and b["cpu_s"] >= 0.0


def test_a_recorded_campaign_counts_every_plant_run_once():
    """A real one-scene campaign, serial, two plants: every recorded task has a kind, the scene
    tasks are the campaign scene's plant runs (one task each), every task took at least its
    plants' time, and the tasks ran one after another inside the campaign's wall."""
    t = bench.time_campaign(
        SerialExecutor(), 1, scenes=1, plants=("analytic", "mujoco"), shrink_evaluations=2
    )
    assert t.scenes == 1 and len(t.of(TaskKind.SCENE)) == 2
    assert len(t.tasks) == sum(len(t.of(k)) for k in TaskKind)
    assert len(t.of(TaskKind.SHRINK)) <= 2 * 2 * max(1, t.counterexamples)
    assert all(x.task_s >= x.plants_s > 0.0 for x in t.tasks)
    assert t.plants_s == pytest.approx(sum(x.plants_s for x in t.tasks))
    assert t.wall_s >= sum(x.task_s for x in t.tasks)  # serial: the tasks ran one after another
    s = t.split()
    assert s["plants"] + s["judging"] + s["startup"] + s["idle"] == pytest.approx(s["total"])
