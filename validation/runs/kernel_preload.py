"""Importing this module loads every plant's numba kernels, for every weighting, into this process,
and runs each plant once over one output interval per weighting (what else a run sets up on first
use: measured, a Pinocchio run forked from a server without it took 175 ms more than with it).

It exists for a fork server's preload (:func:`validation.runs.workers.start_served`): a fork server
only imports modules, and every child it forks inherits what they loaded, so each child's run
finds its kernels in memory instead of loading them from numba's cache again (about 0.5 s per
plant and run, measured: the reason :func:`validation.studies.fuzz.judge.run_limited` loads them
before it forks). The kernels a plant needs depend on the scene only through the solve its
weighting selects (:func:`validation.runs.warmup.compiled_solver`), so one scene per weighting
covers every scene. Loading all of them (three plants x three solves) from a warm cache takes
about 1.8 s with the short runs, once per fork server. A kernel or run that fails is left for the
plant's own run to report (:func:`validation.runs.warmup.run_task` catches it), so this import
never raises for a plant's sake.

Import it only on purpose: it does its work at import.
"""

from __future__ import annotations

from analytic.effects import Weighting
from analytic.scene import load_scene, scene_from_dict
from analytic.scene.dump import scene_to_dict
from validation.runs import warmup

BASE_SCENE = "paper_example1_controlled"
"""The built-in controlled scene whose weighting is varied (any controlled scene serves)."""


def scenes_per_solve() -> list:
    """One controlled scene per weighting of :class:`analytic.effects.Weighting`."""
    data = scene_to_dict(load_scene(BASE_SCENE))
    out = []
    for w in Weighting:
        data["control"]["weighting"] = w.value
        out.append(scene_from_dict(data))
    return out


def load_all() -> list[warmup.StageTime]:
    """Load (or compile) every kernel of every plant of :data:`validation.runs.warmup.ENGINES` for
    every solve here, then run each plant over one output interval per solve (warmup's plant
    jobs); each job's :class:`validation.runs.warmup.StageTime`."""
    pairs = [
        (sc, e) for sc in scenes_per_solve() for e in warmup.ENGINES if warmup.supported(sc, e)
    ]
    kernels, plants = warmup.tasks_for(pairs)
    return [warmup.run_task(t) for t in kernels + plants]


LOADED = load_all()
"""What the import loaded: one :class:`validation.runs.warmup.StageTime` per kernel job."""
