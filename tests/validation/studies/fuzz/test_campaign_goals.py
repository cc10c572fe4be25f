"""The campaign goals' verdicts (:mod:`validation.studies.fuzz.campaign_goals`): a goal read as a
ratio at most its limit, and TOO_BUSY when other processes took CPUs during its campaign, from
planted task times (the timings themselves are the benchmark's to print, never a test's)."""

from __future__ import annotations

import pytest

from validation.bench.goal import Goal
from validation.bench.verdicts import Verdict
from validation.studies.fuzz import campaign_goals as cg
from validation.studies.fuzz.campaign_timing import CampaignTiming, TaskKind, TaskTime


def _task(kind, plants_s, start, end):
    return TaskTime(kind, plants_s, end - start, 0.0, start, end, 1)


def test_other_processes_cpu_makes_a_campaign_goal_too_busy():
    """The machine busy 30 CPU-seconds over a 10 s campaign whose parent used 1 s and whose
    tasks ran 7 s in all: other processes used at least (30 - 1 - 7) / 10 = 2.2 CPUs."""
    tasks = (_task(TaskKind.SCENE, 3.0, 0.0, 4.0), _task(TaskKind.SCENE, 2.0, 0.0, 3.0))
    t = CampaignTiming(10.0, 2, tasks, 0.0, 2, 0, machine_busy_s=30.0, parent_cpu_s=1.0)
    assert t.others_cpus == pytest.approx(2.2)
    g = Goal("c", 1.0, cg.CAMPAIGN_WALL_LIMIT)
    assert cg.campaign_verdict(g, t.others_cpus) is Verdict.TOO_BUSY
    assert cg.campaign_verdict(g, cg.OTHERS_BOUND_CPUS) is Verdict.HOLDS
    assert cg.campaign_verdict(g, None) is Verdict.HOLDS
    assert CampaignTiming(10.0, 2, tasks, 0.0, 2, 0).others_cpus is None


def test_the_goals_read_as_ratios_at_most_their_limits():
    """Two Dask workers 1.7 times as fast as one is a wall ratio of 1/1.7; a campaign exactly at
    1.3 x its plants' compute holds, just above it fails."""
    assert cg.DASK_RATIO_LIMIT == pytest.approx(1 / cg.DASK_SPEEDUP_GOAL)
    assert Goal("c", 1.3, cg.CAMPAIGN_WALL_LIMIT).verdict is Verdict.HOLDS
    assert Goal("c", 1.31, cg.CAMPAIGN_WALL_LIMIT).verdict is Verdict.FAILS
