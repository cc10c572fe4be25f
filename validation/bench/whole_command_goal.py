"""The whole-command goals (:func:`goal_whole_command`): ``tumble validate`` on the default scene in
new processes, warm against the plants' compute, and cold (an empty numba cache) against warm.

They time new processes (a pool of workers: their CPU time is not their wait), by wall; their
:data:`FIRST_RUN_PAIRS` pairs give the spread.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from mj_bridge.registry import BUILTIN, plugin_names
from validation.bench.goal import Goal
from validation.bench.verdicts import spread_of

WHOLE_COMMAND_LIMIT = 1.5
"""``tumble validate`` warm: total wall ≤ 1.5 × the plants' compute. What is not the plants
(imports, the comparison, figures, the recording, the files) may cost half as much again."""

COLD_WARM_LIMIT = 3.0
"""``tumble validate`` cold (an empty numba cache) / warm: a first run may take three times a later
one (it compiles every kernel once, with numba's documented API only, announced with its measured
estimate; ``tumble warmup`` pays it ahead, e.g. when a Docker image is built)."""


def _plant_names() -> tuple[str, ...]:
    """Every plant name of this installation (the stages of a run that are plants)."""

    return BUILTIN + plugin_names()


def _validate_once(out: str, env: dict[str, str]) -> tuple[float, dict[str, float]]:
    """Wall of one ``python -m validation validate`` (default scene, every installed plant) in a
    new process, s, and its ``report.json`` stage walls."""

    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "validation", "validate", "--out", out],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(
            f"tumble validate exited {proc.returncode}: {proc.stderr.strip()[-300:]}"
        )
    doc = json.loads((Path(out) / "report.json").read_text(encoding="utf-8"))
    return wall, {k: float(v) for k, v in doc["run"]["wall_times_s"].items()}


FIRST_RUN_PAIRS = 3
"""Cold/warm pairs timed for the first-run goal, each in its own empty numba cache; the goal is
their median ratio."""


def goal_whole_command(progress: Callable[[str], None] = print) -> tuple[Goal, Goal]:
    """The command a user waits for: ``tumble validate`` on the default scene in a new process.

    :data:`FIRST_RUN_PAIRS` pairs, each a cold run (numba's cache pointed at an empty directory,
    ``NUMBA_CACHE_DIR``; the user's own cache is not touched) followed at once by a warm run in
    the same, now filled, directory. A pair is timed back to back because the machine's speed
    drifts (``docs/performance.md``, Speed goals' margins): a cold run and a warm one from
    different minutes would measure the drift. Returns the goal "warm wall / plants' compute" (the plants' stage walls in ``report.json``), the median over the
    warm runs, and the goal "cold wall / warm wall", the median of the pairs' ratios; each with the
    spread of its per-pair ratios. Timed by wall: the run is several processes (a pool of workers)
    whose waiting for each other is part of what the user waits for."""

    progress(
        f"timing tumble validate in new processes: {FIRST_RUN_PAIRS} x (cold in an empty numba "
        "cache, then warm)"
    )
    pairs = []
    for i in range(FIRST_RUN_PAIRS):
        with tempfile.TemporaryDirectory(prefix="tumble-bench-") as tmp:
            env = dict(os.environ, NUMBA_CACHE_DIR=os.path.join(tmp, "numba"))
            cold, _ = _validate_once(os.path.join(tmp, "cold"), env)
            warm = _validate_once(os.path.join(tmp, "warm"), env)
        pairs.append((cold, warm))
        progress(f"  pair {i + 1}: cold {cold:.1f} s, warm {warm[0]:.1f} s")

    def plants_of(stages: dict[str, float]) -> float:
        return sum(v for k, v in stages.items() if k in _plant_names())

    whole_ratios = [w / plants_of(stages) for _, (w, stages) in pairs]
    whole_spread = spread_of(whole_ratios)
    wall, stages = sorted((w for _, w in pairs), key=lambda w: w[0])[len(pairs) // 2]
    plants = plants_of(stages)
    rest = {k: round(v, 2) for k, v in stages.items() if k not in _plant_names()}
    whole = Goal(
        "tumble validate warm: total wall / plants' compute",
        whole_spread.median,
        WHOLE_COMMAND_LIMIT,
        f"median warm run {wall:.2f} s / {plants:.2f} s (other stages, s: {rest})",
        data={"wall_s": wall, "plants_s": plants, "stages_s": stages, "ratios": whole_ratios},
        spread=whole_spread,
    )
    ratios = [cold / warm[0] for cold, warm in pairs]
    cold, (warm, _) = pairs[ratios.index(statistics.median_low(ratios))]
    first = Goal(
        "tumble validate: cold (empty numba cache) / warm wall, median of pairs",
        statistics.median(ratios),
        COLD_WARM_LIMIT,
        f"{cold:.1f} s / {warm:.1f} s (pairs: "
        + ", ".join(f"{c:.1f}/{w[0]:.1f}" for c, w in pairs)
        + ")",
        data={"pairs_s": [[c, w[0]] for c, w in pairs], "ratios": ratios},
        spread=spread_of(ratios),
    )
    return whole, first


__all__ = ["COLD_WARM_LIMIT", "FIRST_RUN_PAIRS", "WHOLE_COMMAND_LIMIT", "goal_whole_command"]
