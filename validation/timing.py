"""What the benchmarks share: the scene they time and the timing loop.

:func:`chain_scene` builds the controlled scene of n masses that :mod:`validation.bench`,
:mod:`validation.goals` and :mod:`validation.fast_bench` time; :func:`time_call` is the median-of-
batches timing loop of the first and last of these. Both live here, below the three benchmark
modules, so that none of them imports another (the import graph has no cycles,
``tests/test_layers.py``).
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from analytic.scene import Scene, scene_from_dict


def chain_scene(n: int, seed: int = 0) -> Scene:
    """A controlled scene with n masses on a generic rod (not through C), all masses tracked."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=3)
    a /= np.linalg.norm(a)
    p_e = np.linspace(-0.4 * n, 0.4 * n, n) if n > 1 else np.zeros(n)
    data = {
        "scene": {
            "name": f"bench_chain_{n}",
            "effects": [
                "gravity",
                "springs.linear",
                "springs.cubic",
                "mass_inertia",
                "control.omega",
                "control.masses",
            ],
        },
        "body": {"mass": 1e4, "inertia": [3e4, 4e4, 5e4]},
        "rod": {"axis": a.tolist(), "offset": [0.3, -0.2, 0.1]},
        "masses": {
            "mass": (1e3 * (1 + rng.random(n))).tolist(),
            "p_e": p_e.tolist(),
            "ring_radius": [0.2] * n,
        },
        "springs": {"k_linear": [1e5] * (n + 1), "k_cubic": [1e3] * (n + 1)},
        "initial": {
            "Rdot": [1, 2, 3],
            "omega": [0.3, -0.2, 0.5],
            "p": (p_e + 0.1).tolist(),
            "attitude": {"axis": [1, 1, 1], "angle_deg": 30},
        },
        "control": {
            "omega": {"b": [1, 0.5, -0.5], "sigma": [0, 1, 2], "gamma": 0.5},
            "masses": {"l": [0.2] * n, "lambda": [1.0] * n, "alpha": [2.0] * n, "beta": [12.0] * n},
        },
    }
    return scene_from_dict(data)


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
