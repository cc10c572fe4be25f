"""The batched throughput benchmark (:mod:`validation.bench.batch_throughput`) with a fake batched
plant (``tests/support/plugin_batched``): the scenes it times share one structure, each batch
size is one call of the batched plant against the C plant's loop over the same scenes, the figures
are the ratios of what was timed, and a plant that refuses or fails is said so. No speed is
asserted."""

from __future__ import annotations

import math
import sys

import pytest

from tests.support.batched_plants import BatchedEchoPlant, RaisingBatchPlant
from validation.bench import batch_throughput as bt

SIZES = (1, 3)
"""Small batches: the benchmark's arithmetic, not its speed, is under test."""
DEVICES = {"JAX": "cpu:0 (planted)"}


class CountingEcho(BatchedEchoPlant):
    """The fake batched plant, counting the batch sizes it is called with."""

    def __init__(self):
        super().__init__()
        self.calls: list[int] = []

    def _simulate_batch(self, scenes, settings, t_end, progress):
        self.calls.append(len(scenes))
        return super()._simulate_batch(scenes, settings, t_end, progress)


def test_the_scenes_share_one_structure_and_differ():
    scenes = bt.batch_scenes(4, dt=1e-3)
    assert len({(s.n, s.effects) for s in scenes}) == 1
    assert len({tuple(s.initial.omega) for s in scenes}) == 4
    assert {s.mujoco.timestep for s in scenes} == {1e-3}
    assert [s.name for s in scenes] == [f"{bt.BASE_SCENE}_batch{i}" for i in range(4)]
    assert [s.name[-3:] for s in bt.batch_scenes(11)][9:] == ["h09", "h10"]  # one length
    with pytest.raises(ValueError, match=r"^count: "):
        bt.batch_scenes(0)


def test_each_size_is_one_batched_call_against_the_c_loop():
    lines: list[str] = []
    pl = CountingEcho()
    (goal,) = bt.goal_batched_throughput(
        [pl], sizes=SIZES, horizon=bt.HORIZON_S, progress=lines.append, devices=DEVICES
    )
    assert pl.calls == [1, *SIZES]  # the first call (not counted), then one call per size
    assert not goal.skipped and goal.limit == bt.THROUGHPUT_LIMIT
    points = goal.data["points"]
    assert [p["size"] for p in points] == list(SIZES)
    for p in points:
        assert p["scenes_per_s"] == pytest.approx(p["size"] / p["wall_s"])
        assert p["c_loop_scenes_per_s"] == pytest.approx(p["size"] / p["c_loop_wall_s"])
        assert p["speedup"] == pytest.approx(p["c_loop_wall_s"] / p["wall_s"])
        assert p["failed"] == 0
    assert goal.value == pytest.approx(1.0 / points[-1]["speedup"])
    text = "\n".join(lines)
    assert "devices: JAX cpu:0 (planted)" in text
    assert f"({round(bt.HORIZON_S / bt.DT_S)} steps)" in text
    assert sum(1 for x in lines if x.split()[:1] in (["1"], ["3"])) == len(SIZES)  # table rows


def test_a_plant_that_refuses_the_scene_or_fails_is_said_so():
    class Refusing(BatchedEchoPlant):
        engine = "refusing"
        effects = frozenset()

    refused, failed = bt.goal_batched_throughput(
        [Refusing(), RaisingBatchPlant()], sizes=(1,), progress=lambda _s: None, devices={}
    )
    assert refused.skipped.startswith("it refuses the scene: scene.effects:")
    assert failed.value == math.inf and "a run failed: lost its device" in failed.detail
    assert failed.verdict == "FAILS"


def test_no_batched_plant_skips_the_goal():
    (goal,) = bt.goal_batched_throughput([], sizes=(1,), devices={})
    assert goal.skipped.startswith("no batched plant is installed")


def test_bad_sizes_are_refused():
    with pytest.raises(ValueError, match=r"^sizes: "):
        bt.goal_batched_throughput([BatchedEchoPlant()], sizes=(0, 2), devices={})


def test_devices_are_asked_in_a_new_process_and_a_failure_says_why(monkeypatch):
    monkeypatch.setattr(
        bt,
        "DEVICE_PROBES",
        {
            "Fake": ("json", "print('noise'); print('cuda:0 (Planted GPU)')"),
            "Broken": ("json", "raise SystemExit('no driver')"),
            "Absent": ("no_such_module_here", "print('never')"),
        },
    )
    loaded = {"jax", "warp"} & set(sys.modules)
    got = bt.accelerator_devices(timeout_s=60)
    assert got == {"Fake": "cuda:0 (Planted GPU)", "Broken": "unknown (no driver)"}
    assert {"jax", "warp"} & set(sys.modules) == loaded  # nothing imported here


def test_a_batch_size_that_fails_keeps_the_sizes_measured_before_it():
    class SmallOnly(BatchedEchoPlant):
        def _simulate_batch(self, scenes, settings, t_end, progress):
            if len(scenes) > 1:
                raise MemoryError("out of device memory")
            return super()._simulate_batch(scenes, settings, t_end, progress)

    lines: list[str] = []
    (goal,) = bt.goal_batched_throughput(
        [SmallOnly()], sizes=SIZES, progress=lines.append, devices={}
    )
    assert [p["size"] for p in goal.data["points"]] == [1]
    assert goal.value == math.inf and goal.verdict == "FAILS"
    assert "the batch of 3 failed: out of memory" in goal.detail
