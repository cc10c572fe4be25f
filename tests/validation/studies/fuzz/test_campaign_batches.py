"""A campaign with a batched plant (:mod:`validation.studies.fuzz.campaign_batches`): its scenes of
one structure go to it as one batch per block, its verdicts are the ones its per-scene path gives,
and a batch that fails fails that plant's runs only."""

from __future__ import annotations

from analytic.scene import scene_from_dict
from tests.support.batched_plants import BatchedEchoPlant, LoopedEchoPlant, RaisingBatchPlant
from validation.runs.ordered import SerialExecutor
from validation.studies.fuzz.campaign import fuzz
from validation.studies.fuzz.campaign_batches import BATCH_BLOCK, batched_plants
from validation.studies.fuzz.judge import Disagreement, Kind
from validation.studies.fuzz.space import draw_scene_dict

SEED, BUDGET, HORIZON_S = 1, 7, 0.1
"""Scenes 0-6 of seed 1: scenes 3 and 5 share a structure, so do 4 and 6 (no masses; gravity,
a given torque), the others are alone in theirs."""


class Recording(SerialExecutor):
    """A serial executor that keeps the name and the arguments of every task."""

    def __init__(self):
        self.tasks = []

    def submit(self, fn, /, *args, **kwargs):
        self.tasks.append((fn.__name__, args))
        return super().submit(fn, *args, **kwargs)


def _strip(d):
    return {k: v for k, v in d.items() if k != "walls"}


def test_the_scene_space_has_the_structures_the_tests_rely_on():
    assert BUDGET <= BATCH_BLOCK
    s = [scene_from_dict(draw_scene_dict(SEED, i, HORIZON_S)) for i in range(BUDGET)]
    assert (s[3].n, s[3].effects) == (s[5].n, s[5].effects) == (0, s[3].effects)
    assert (s[4].n, s[4].effects) == (s[6].n, s[6].effects) != (s[3].n, s[3].effects)


def test_batched_plants_are_found_by_their_flag():
    assert batched_plants(["analytic", BatchedEchoPlant(), LoopedEchoPlant()]) == {"batched_echo"}
    assert batched_plants(["analytic", "mujoco"]) == frozenset()


def test_a_batched_plant_gets_batches_and_the_verdicts_of_its_per_scene_path(tmp_path):
    ex = Recording()
    got = fuzz(tmp_path / "b", budget=BUDGET, seed=SEED, plants=["analytic", BatchedEchoPlant()],
               horizon=HORIZON_S, executor=ex, report=False)  # fmt: skip
    batches = sorted(tuple(args[1]) for name, args in ex.tasks if name == "batch_plant_task")
    assert batches == [(0,), (1,), (2,), (3, 5), (4, 6)]
    singles = [args[1] for name, args in ex.tasks if name == "scene_plant_task"]
    assert singles == list(range(BUDGET))  # the analytic plant's, scene by scene, in order
    want = fuzz(tmp_path / "l", budget=BUDGET, seed=SEED, plants=["analytic", LoopedEchoPlant()],
                horizon=HORIZON_S, executor=SerialExecutor(), report=False)  # fmt: skip
    assert [_strip(r.outcome.to_dict()) for r in got.scenes] == [
        _strip(r.outcome.to_dict()) for r in want.scenes
    ]
    assert all(r.outcome.ran == ("analytic", "batched_echo") for r in got.scenes)


def test_a_failing_batch_fails_that_plants_runs_only(tmp_path):
    res = fuzz(tmp_path, budget=BUDGET, seed=SEED, shrink_evaluations=1,
               plants=["analytic", LoopedEchoPlant(), RaisingBatchPlant()],
               horizon=HORIZON_S, executor=SerialExecutor(), report=False)  # fmt: skip
    raised = Disagreement(Kind.RAISED, "RuntimeError", "raising_batch")
    for r in res.scenes:
        o = r.outcome
        assert o.ran == ("analytic", "batched_echo") and raised in o.disagreements
        assert "raising_batch" in o.messages and "lost its device" in o.messages["raising_batch"]
        assert o.checks["analytic_vs_batched_echo.position_C"][2] == "pass"


def test_a_resumed_campaign_batches_only_the_scenes_left(tmp_path):
    fuzz(tmp_path, budget=4, seed=SEED, plants=["analytic", BatchedEchoPlant()],
         horizon=HORIZON_S, executor=SerialExecutor(), report=False)  # fmt: skip
    ex = Recording()
    res = fuzz(tmp_path, budget=BUDGET, seed=SEED, plants=["analytic", BatchedEchoPlant()],
               horizon=HORIZON_S, executor=ex, report=False)  # fmt: skip
    batches = sorted(tuple(args[1]) for name, args in ex.tasks if name == "batch_plant_task")
    assert batches == [(4, 6), (5,)]  # 0-3 judged before: read back, not run again
    assert [r.index for r in res.scenes] == list(range(BUDGET))
