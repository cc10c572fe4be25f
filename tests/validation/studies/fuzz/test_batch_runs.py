"""A batched plant's runs of many scenes in one call (:mod:`validation.studies.fuzz.batch_runs`):
each scene's run is the single run's, checked against the plant contract on its own; a batch that
raises, breaks the contract as a whole or passes its limit fails that plant's runs of every scene
of the batch, and only those."""

from __future__ import annotations

import time
import warnings

import numpy as np

from analytic.scene import scene_from_dict
from tests.support.batched_plants import (
    BatchedEchoPlant,
    BrokenFirstPlant,
    RaisingBatchPlant,
    ShortBatchPlant,
    SleepyBatchPlant,
)
from tests.support.fuzz_plants import SLEEP_S
from validation.studies.fuzz.batch_runs import batch_plant_task, batch_runs, structure_key
from validation.studies.fuzz.judge import RUN_BUDGET_S, run_one
from validation.studies.fuzz.space import draw_scene_dict

SEED, INDICES, HORIZON_S = 1, (3, 5), 0.1
"""Campaign scenes 3 and 5 of seed 1 share one structure (no masses, gravity on)."""


def _scenes():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return [scene_from_dict(draw_scene_dict(SEED, i, HORIZON_S)) for i in INDICES]


def test_the_batch_gives_each_scene_its_single_run():
    scenes = _scenes()
    assert len({structure_key(s) for s in scenes}) == 1
    runs = batch_plant_task(SEED, INDICES, BatchedEchoPlant(), HORIZON_S, RUN_BUDGET_S)["runs"]
    assert [r.name for r in runs] == ["batched_echo"] * 2
    for r, scene in zip(runs, scenes, strict=True):
        single = run_one("batched_echo", BatchedEchoPlant(), scene, HORIZON_S, RUN_BUDGET_S)
        assert not r.raised and not r.message and r.traj.scene == scene.name
        assert r.traj.info["batch_size"] == 2 and single.traj.info["batch_size"] == 1
        np.testing.assert_array_equal(r.traj.q, single.traj.q)  # the same integration, here
        assert r.wall > 0


def test_a_batch_that_raises_fails_every_scene_of_it_for_that_plant():
    runs = batch_runs("raising_batch", RaisingBatchPlant(), _scenes(), HORIZON_S, RUN_BUDGET_S)
    assert len(runs) == 2
    for r in runs:
        assert r.traj is None and r.raised == "RuntimeError"
        assert "lost its device with 2 worlds" in r.message


def test_a_broken_trajectory_fails_its_own_scene_only():
    runs = batch_runs("broken_first", BrokenFirstPlant(), _scenes(), HORIZON_S, RUN_BUDGET_S)
    assert runs[0].traj is None and runs[0].raised == "ContractError"
    assert runs[0].message.startswith("broke the plant contract: q has shape")
    assert runs[1].traj is not None and not runs[1].raised


def test_a_batch_of_the_wrong_length_fails_every_scene():
    runs = batch_runs("short_batch", ShortBatchPlant(), _scenes(), HORIZON_S, RUN_BUDGET_S)
    assert {r.raised for r in runs} == {"ContractError"}
    assert runs[0].message == (
        "broke the plant contract: simulate_batch returned 1 items for 2 scenes"
    )


def test_a_batch_is_stopped_at_the_sum_of_its_scenes_limits():
    limit_s = 0.5
    t0 = time.perf_counter()
    runs = batch_runs("sleepy_batch", SleepyBatchPlant(), _scenes(), HORIZON_S, limit_s)
    assert time.perf_counter() - t0 < 0.25 * SLEEP_S  # stopped, not slept through
    assert {r.limit_s for r in runs} == {2 * limit_s}
    assert all(r.traj is None and "over its time limit" in r.message for r in runs)


def test_a_refused_scene_refuses_the_batch_task():
    class NoGravity(BatchedEchoPlant):
        effects = BatchedEchoPlant.effects - {next(iter(_scenes()[0].effects))}

    runs = batch_plant_task(SEED, INDICES, NoGravity(), HORIZON_S, RUN_BUDGET_S)["runs"]
    assert {r.raised for r in runs} == {"ValueError"}
    assert runs[0].message.startswith("scenes[0]: ValueError: scene.effects:")


def test_an_empty_batch_runs_nothing():
    assert batch_runs("batched_echo", BatchedEchoPlant(), [], HORIZON_S, RUN_BUDGET_S) == []
