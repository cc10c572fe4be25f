"""The campaign's throughput, measured in one process: scene-validations per core-minute.

One validation is what a campaign does per scene: every plant's run at the scene's default
settings, :func:`validation.compare.compare_plants` and the referee, no figure, recording or file
(:func:`validation.studies.fuzz.judge.judge_scene`). Measured on the controlled Example 1 over a
2 s horizon with the three plants (the goal: at least
:data:`GOAL_PER_CORE_MINUTE`), by this thread's CPU time, so the figure is per core whatever else
the machine runs; the plants' own share (their wall times) is reported beside it.

``python -m validation.studies.fuzz.bench [ROUNDS]`` prints one line per figure.
"""

from __future__ import annotations

import statistics
import sys
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


def measure(rounds: int = 5, plants: tuple[str, ...] = ("analytic", "mujoco", "pinocchio")) -> Throughput:
    """:class:`Throughput` over ``rounds`` validations (after one unmeasured, which loads the
    compiled kernels)."""

    data = scene_to_dict(resolve_scene(SCENE))
    data["output"]["t_end"] = HORIZON_S
    judge_scene(data, plants, HORIZON_S)
    cpu, comp = [], []
    for _ in range(rounds):
        c0 = time.thread_time()
        out = judge_scene(data, plants, HORIZON_S)
        cpu.append(time.thread_time() - c0)
        comp.append(sum(out.walls.values()))
    c = statistics.median(cpu)
    return Throughput(c, statistics.median(comp), 60.0 / c, rounds)


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    t = measure(int(args[0]) if args else 5)
    print(f"one validation of {SCENE} over {HORIZON_S:g} s, three plants: CPU {t.cpu_s:.3f} s "
          f"(plants {t.plants_s:.3f} s wall), {t.per_core_minute:.0f} per core-minute "
          f"(goal ≥ {GOAL_PER_CORE_MINUTE:g}: {'holds' if t.per_core_minute >= GOAL_PER_CORE_MINUTE else 'fails'})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
