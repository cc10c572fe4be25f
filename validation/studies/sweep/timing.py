"""What a setting costs: its wall time as the engine measures it (the integration only), the
median of a few runs and their spread.

The first timing of a setting is its accuracy run (:mod:`validation.studies.sweep.series`); it is repeated
only where that is cheap: up to ``repeats`` timings in all, and none once the setting's timings
add up to ``repeat_budget_s`` (a run of a few ms is timed three times, a run of seconds once). A
series warms its plant and method up first (:func:`warm_up`: JIT compilation or loading, cache
loads and first-call imports stay outside every timing).
"""

from __future__ import annotations

import statistics
from collections.abc import Sequence
from typing import Any

from analytic.scene import Scene
from validation.studies.sweep import running
from validation.studies.sweep.config import SweepConfig


def warm_up(scene: Scene, engine: str, method: str, setting: float, cfg: SweepConfig) -> None:
    """One output interval of ``engine`` / ``method`` at ``setting``, untimed."""
    running.run_setting(scene, engine, method, setting, cfg, t_end=1.0 / scene.output.rate)


def wall_of(tr) -> float:
    """A run's wall time as its engine measured it (the integration loop), s."""
    return float(tr.info["wall_time_s"])


def timings(
    scene: Scene, engine: str, method: str, setting: float, cfg: SweepConfig, first: float
) -> list[float]:
    """Every timing of a setting, s: ``first`` (its accuracy run's) and repeats of the same run
    while fewer than ``cfg.repeats`` (an accelerated plant's: ``cfg.accelerated_repeats``) and
    adding up to less than ``cfg.repeat_budget_s``."""
    samples = [first]
    while len(samples) < cfg.repeats_for(engine) and sum(samples) < cfg.repeat_budget_s:
        samples.append(wall_of(running.run_setting(scene, engine, method, setting, cfg)))
    return samples


def summary(samples: Sequence[float]) -> dict[str, Any]:
    """The timing columns of a row: median, min and max of ``samples`` and how many."""
    if not samples:
        return {"wall_time_s": None, "wall_time_min_s": None, "wall_time_max_s": None,
                "wall_time_repeats": 0}  # fmt: skip
    return {
        "wall_time_s": float(statistics.median(samples)),
        "wall_time_min_s": float(min(samples)),
        "wall_time_max_s": float(max(samples)),
        "wall_time_repeats": len(samples),
    }


__all__ = ["summary", "timings", "wall_of", "warm_up"]
