"""Two plants' whole runs timed in alternating rounds (:func:`plant_rounds`), for the plant goals
(:mod:`validation.bench.pinocchio_goal`, :mod:`validation.bench.drake_goal`): each run's
integration counted as its wall times the share of a CPU the thread had during it
(:class:`validation.bench.timing.CpuMeter`)."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

from mj_bridge.plants import AnalyticSettings, plant
from validation.bench.timing import CpuMeter


@dataclass(frozen=True)
class PlantRounds:
    """Two plants' 20 s runs timed in alternating rounds (:func:`plant_rounds`).

    Attributes:
        first: name -> ``(trajectory, wall, call, cpu)`` of the warm-up run (compilation and
            cache loads), s.
        default_loop: the analytic plant's run on its default loop at the same tolerances.
        walls, calls, cpus: name -> per-round integration wall, whole ``simulate`` call and
            integration CPU time, s.
        order: who went first in each round.
    """

    first: dict[str, tuple[Any, float, float, float]]
    default_loop: Any
    walls: dict[str, list[float]]
    calls: dict[str, list[float]]
    cpus: dict[str, list[float]]
    order: list[list[str]]


def plant_rounds(sc, runs: dict[str, tuple[Any, Any]], t_end: float, rounds: int) -> PlantRounds:
    """Each of ``runs`` (name -> ``(plant, settings)``) once to warm up, then ``rounds`` rounds
    alternating who goes first, each run's integration CPU time measured by a :class:`CpuMeter`;
    ``RuntimeError`` naming the plant whose run did not finish."""

    def once(name: str):
        pl, settings = runs[name]
        meter = CpuMeter()
        t0 = time.perf_counter()
        with meter:
            tr = pl.simulate(sc, settings, t_end=t_end, progress=meter).raise_if_interrupted()
        call = time.perf_counter() - t0
        if tr.status.value != "ok":
            raise RuntimeError(f"{name} plant: {tr.message}")
        wall = float(tr.info["wall_time_s"])
        return tr, wall, call, meter.cpu_of(wall)

    first = {name: once(name) for name in runs}
    default_loop = plant("analytic").simulate(
        sc, AnalyticSettings("DOP853", 1e-12, 1e-13), t_end=t_end
    )
    walls: dict[str, list[float]] = {name: [] for name in runs}
    calls: dict[str, list[float]] = {name: [] for name in runs}
    cpus: dict[str, list[float]] = {name: [] for name in runs}
    order = []
    for k in range(rounds):
        names = list(runs) if k % 2 == 0 else list(reversed(runs))  # alternate who goes first
        order.append(names)
        for name in names:
            _, wall, call, cpu = once(name)
            walls[name].append(wall)
            calls[name].append(call)
            cpus[name].append(cpu)
    return PlantRounds(first, default_loop, walls, calls, cpus, order)


__all__ = ["PlantRounds", "plant_rounds"]
