"""Every plant made ready to run in this process, per solve, without running the scene at hand.

A plant's first run in a process pays more than its numba kernels: modules it imports on first
use, first calls through compiled dispatchers, engine set-up. Measured on the controlled
Example 1 over 2 s: a Pinocchio run forked from a process that had only loaded its kernels took
0.52 s, from one that had also run the plant once 0.05 s (the run itself, in-process, 0.05 s);
the children of one validation of three plants used 0.38 s and 0.20 s of CPU. So a process that
forks plant runs (:func:`validation.studies.fuzz.judge.run_limited`, the fork server's preload
:mod:`validation.runs.kernel_preload`) first loads the kernels and runs each plant over one
output interval, here, once per plant and solve.

The scene of that run is a built-in one with the solve's weighting, never the scene at hand: a
run here has no time limit, and the scene at hand may be one that takes far longer than it should
(the reason it is run under a limit). The kernels a plant needs depend on a scene only through
the solve its weighting selects (:func:`validation.runs.warmup.compiled_solver`), so the
built-in scene loads the same ones. A failure is left for the plant's own run to report
(:func:`validation.runs.warmup.run_task` catches it).
"""

from __future__ import annotations

import functools

from analytic.effects import Weighting
from analytic.scene import Scene, load_scene, scene_from_dict
from analytic.scene.dump import scene_to_dict
from validation.runs import warmup

BASE_SCENE = "paper_example1_controlled"
"""The built-in controlled scene whose weighting is varied (any controlled scene serves)."""


@functools.cache
def scenes_per_solve() -> dict[int | None, Scene]:
    """solve (:func:`validation.runs.warmup.compiled_solver`) -> a built-in controlled scene with
    a weighting that selects it (the first such weighting of :class:`analytic.effects.Weighting`;
    the key is None for every scene when numba is absent)."""
    data = scene_to_dict(load_scene(BASE_SCENE))
    out: dict[int | None, Scene] = {}
    for w in Weighting:
        data["control"]["weighting"] = w.value
        scene = scene_from_dict(data)
        out.setdefault(warmup.compiled_solver(scene), scene)
    return out


_WARM: set[tuple[str, int | None]] = set()
"""(plant, solve) made ready in this process."""


def warm(name: str, solver: int | None) -> list[warmup.StageTime]:
    """Plant ``name`` ready for scenes of solve ``solver`` (module docstring), once per process:
    its kernels loaded (or compiled) and one output interval run on the built-in scene of that
    solve. Each job's :class:`validation.runs.warmup.StageTime` (none when done before, when the
    plant needs no kernels, or when no scene selects ``solver``)."""
    key = (name, solver)
    if key in _WARM or name not in warmup.KERNELS:
        return []
    _WARM.add(key)
    scene = scenes_per_solve().get(solver)
    if scene is None or not warmup.supported(scene, name):
        return []
    kernels, plants = warmup.tasks_for([(scene, name)])
    return [warmup.run_task(t) for t in kernels + plants]


def warm_all() -> list[warmup.StageTime]:
    """:func:`warm` for every plant of :data:`validation.runs.warmup.ENGINES` and every solve."""
    return [st for s in scenes_per_solve() for e in warmup.ENGINES for st in warm(e, s)]
