"""What the hard time limit costs per plant run (:func:`served_overhead`): a run forked from this
process (single-threaded) against one forked by the fork server (what a multi-threaded process, a
Dask worker, uses), against the same run made here.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

from analytic.scene import Scene, scene_from_dict
from analytic.scene.dump import scene_to_dict
from mj_bridge.plants import plant
from validation.runs import workers
from validation.scenes import resolve_scene
from validation.studies.fuzz.judge import _simulate_task, run_limited
from validation.studies.fuzz.throughput import SCENE


@dataclass(frozen=True)
class LimitOverhead:
    """Median wall of one plant run, s: made here (``here_s``), forked from this process
    (``fork_s``), forked by the fork server (``served_s``); over ``rounds`` alternating rounds
    (the first served run, which starts the server and its preload, excluded: ``server_start_s``)."""

    plant: str
    here_s: float
    fork_s: float
    served_s: float
    server_start_s: float
    rounds: int

    def text(self) -> str:
        ms = 1e3
        return (
            f"{self.plant}: run here {self.here_s * ms:.1f} ms; forked +"
            f"{(self.fork_s - self.here_s) * ms:.1f} ms; fork server +"
            f"{(self.served_s - self.here_s) * ms:.1f} ms (medians of {self.rounds}; the server's "
            f"first run, with its start and preload, {self.server_start_s:.2f} s)"
        )


def _fresh_scenes(horizon_s: float) -> Callable[[], Scene]:
    """A new scene at every call: the controlled Example 1 over ``horizon_s`` with C's initial
    velocity changed by a further 1e-6 m/s along x (the same cost; no per-scene cache of a plant
    serves it, as none serves a campaign's random scenes)."""
    data = scene_to_dict(resolve_scene(SCENE))
    data["output"]["t_end"] = horizon_s
    count = [0]

    def make() -> Scene:
        count[0] += 1
        data["initial"]["Rdot"][0] = 1.0 + 1e-6 * count[0]
        return scene_from_dict(data)

    return make


def served_overhead(
    name: str = "analytic", rounds: int = 15, horizon_s: float = 0.05
) -> LimitOverhead:
    """:class:`LimitOverhead` of plant ``name`` on the controlled Example 1 over ``horizon_s``
    (short, so the run is mostly overhead), every run on a scene not run before
    (:func:`_fresh_scenes`), as in a campaign. The fork path needs this process single-threaded
    (:func:`validation.runs.workers.can_fork`); the served runs are made from a helper thread, as
    a Dask worker's task thread makes them. ``ValueError`` naming ``name`` when forking is not
    possible here."""
    if not (workers.can_fork() and workers.can_serve()):
        raise ValueError(f"name: {name!r}: this process cannot fork (threads, or not Linux)")
    fresh = _fresh_scenes(horizon_s)
    pl = plant(name)
    limit = 60.0

    def here() -> float:
        sc = fresh()
        t0 = time.perf_counter()
        _simulate_task(pl, sc, horizon_s)
        return time.perf_counter() - t0

    def limited() -> float:
        sc = fresh()
        t0 = time.perf_counter()
        run_limited(name, pl, sc, horizon_s, limit)
        return time.perf_counter() - t0

    here()
    limited()  # loads the kernels here
    runs: dict[str, list[float]] = {"here": [], "forked": [], "served": []}
    with ThreadPoolExecutor(1) as thread:
        first = thread.submit(limited).result()
        for _ in range(rounds):
            runs["here"].append(here())
            runs["served"].append(thread.submit(limited).result())
    for _ in range(rounds):  # the thread is gone: this process may fork again
        runs["forked"].append(limited())
        runs["here"].append(here())
    med = {k: statistics.median(v) for k, v in runs.items()}
    return LimitOverhead(name, med["here"], med["forked"], med["served"], first, rounds)
