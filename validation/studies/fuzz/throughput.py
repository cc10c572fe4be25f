"""The campaign's first throughput goal: scene-validations per core-minute.

One validation is what a campaign does per scene: every plant's run at the scene's default
settings, :func:`validation.compare.compare_plants` and the referee, no figure, recording or file
(:func:`validation.studies.fuzz.judge.judge_scene`). :func:`measure` times it on the controlled
Example 1 over a :data:`HORIZON_S` horizon with the three plants (the goal: at least
:data:`GOAL_PER_CORE_MINUTE`), by CPU time (this thread's and that of the child processes the plant
runs are made in), so the figure is per core whatever else the machine runs; the plants' own share
(their wall times) is reported beside it.
"""

from __future__ import annotations

import multiprocessing
import resource
import statistics
import time
from dataclasses import dataclass

from analytic.scene.dump import scene_to_dict
from validation.scenes import resolve_scene
from validation.studies.fuzz.judge import judge_scene

GOAL_PER_CORE_MINUTE = 200.0
"""Scene-validations per core-minute the campaign is meant to reach on Example 1 (2 s, three
plants)."""
SCENE = "paper_example1_controlled"
HORIZON_S = 2.0


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
