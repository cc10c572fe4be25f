"""What the benchmarks share: the scene they time and the timing loop.

:func:`chain_scene` builds the controlled scene of n masses that :mod:`validation.bench.command`,
:mod:`validation.bench.goals` and :mod:`validation.bench.fast_bench` time; :func:`time_call` is the median-of-
batches timing loop of the first and last of these. Both live here, below the three benchmark
modules, so that none of them imports another (the import graph has no cycles,
``tests/cross/test_layers.py``).
"""

from __future__ import annotations

import statistics
import time

from analytic import random_scenes
from analytic.scene import Scene


def chain_scene(n: int, seed: int = 0) -> Scene:
    """A controlled scene with n masses on a generic rod (not through C), every axis of ω and every
    mass tracked: :func:`analytic.random_scenes.chain_scene` (the one random-scene generator)."""
    return random_scenes.chain_scene(n, seed)


def time_call(fn, repeats: int = 7, number: int | None = None) -> float:
    """Median seconds per call of ``fn()`` over ``repeats`` batches of ``number`` calls."""
    if number is None:
        t0 = time.perf_counter()
        fn()
        one = max(time.perf_counter() - t0, 1e-7)
        number = max(1, int(0.05 / one))
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        runs.append((time.perf_counter() - t0) / number)
    return statistics.median(runs)
