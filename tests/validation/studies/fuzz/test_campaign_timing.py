"""A timed campaign's bookkeeping (:mod:`validation.studies.fuzz.campaign_timing`): where its
worker-time goes, from planted task times; the recording executor on a real (tiny) campaign. The
timings themselves are the benchmark's to print, never a test's to assert."""

from __future__ import annotations

import math

import pytest

from validation.studies.fuzz import campaign_timing as timing
from validation.studies.fuzz.campaign import SerialExecutor
from validation.studies.fuzz.campaign_timing import CampaignTiming, TaskKind, TaskTime


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


def test_a_campaign_without_plant_runs_has_no_finite_ratio():
    assert math.isinf(CampaignTiming(1.0, 2, (), 0.0, 0, 0).ratio)


def test_timed_task_keeps_the_outcome_and_adds_its_times():
    out = timing.timed_task(lambda a, b: {"walls": {"x": a}, "ran": [b]}, 0.25, "x")
    assert out["walls"] == {"x": 0.25} and out["ran"] == ["x"]
    b = out[timing.BENCH_KEY]
    assert b["end"] >= b["start"] and b["cpu_s"] >= 0.0


def test_a_recorded_campaign_counts_every_plant_run_once():
    """A real one-scene campaign, serial, two plants: every recorded task has a kind, the scene
    tasks are the campaign scene's plant runs (one task each), every task took at least its
    plants' time, and the tasks ran one after another inside the campaign's wall."""
    t = timing.time_campaign(
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
