"""One batched plant's runs of many scenes of one structure in one call, each scene's run judged alone.

A plant whose :attr:`analytic.plant.Plant.batched` is True runs many scenes of one structure (the
same ``n`` and effects) in one :meth:`analytic.plant.Plant.simulate_batch` call. The campaign
(:mod:`validation.studies.fuzz.campaign_batches`) hands such a plant its scenes that way;
:func:`batch_plant_task` is the executor's task, :func:`batch_runs` the run and its checks.

The trust rules are the per-scene run's (``docs/plugins.md`` §9, :mod:`validation.runs.contract`),
applied per scene:

* the batch runs in a worker process killed at its wall-time limit, the per-scene limit times the
  number of scenes (:func:`run_batch_limited`, as :func:`validation.studies.fuzz.judge.run_limited`);
* what the batch returned for each scene is checked against the plant contract for that scene
  (:func:`validation.studies.fuzz.judge.returned_run`): a broken trajectory fails that plant's run of
  that scene only;
* a batch that raises, passes its limit, loses its worker, or returns anything but a list of one
  trajectory per scene fails **that plant's runs of every scene of the batch** (each the same
  :class:`~validation.studies.fuzz.judge.PlantRun` a single run failing so would give); the other
  plants' runs of those scenes are not touched.

Each run's ``wall`` is the batch's wall time divided by its number of scenes (its share).
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Sequence
from multiprocessing import RawValue
from typing import Any

from analytic.plant import Plant
from analytic.scene import Scene
from analytic.trajectory import Trajectory
from validation.runs import workers
from validation.runs.contract import ContractError
from validation.studies.fuzz.judge import (
    SERVER_PRELOAD,
    OverTime,
    PlantRun,
    _budget_progress,
    _load_kernels,
    _one_line,
    _Raised,
    plant_name,
    prepare,
    resolve_plant,
    returned_run,
)
from validation.studies.fuzz.space import draw_scene_dict


def structure_key(scene: Scene) -> tuple[int, frozenset]:
    """What scenes of one batch share: the number of masses and the effects."""
    return scene.n, scene.effects


def _simulate_batch_task(
    pl: Plant,
    scenes: list[Scene],
    horizon: float,
    reached: Any = None,
    progress=None,
    report=None,
) -> list[Trajectory]:
    """The batch at the plant's default settings (the forked worker's task; ``report`` is not
    used); ``reached``, a shared double, holds the batch's simulated time, s."""

    def told(t: float) -> None:
        if reached is not None:
            reached.value = t
        if progress is not None:
            progress(t)

    with warnings.catch_warnings():  # as a single run: what they say is in each run's status
        warnings.simplefilter("ignore", RuntimeWarning)
        warnings.simplefilter("ignore", UserWarning)
        return pl.simulate_batch(scenes, None, t_end=horizon, progress=told)


def run_batch_limited(
    name: str, pl: Plant, scenes: list[Scene], horizon: float, limit_s: float
) -> Any:
    """What ``pl.simulate_batch(scenes, t_end=horizon)`` returned, run within ``limit_s`` s of wall
    time (forked, served or here, as :func:`validation.studies.fuzz.judge.run_limited`).

    Raises:
        OverTime: the limit passed (the worker, if any, is ended and reaped).
        _Raised: the batch raised (its type name and first line).
        KeyboardInterrupt: an interrupt here or in the worker (the worker is ended).
    """
    reached = RawValue("d", math.nan)
    args = (_simulate_batch_task, pl, scenes, horizon, reached)
    if workers.can_fork():
        _load_kernels(name, scenes[0])
        job = workers.start(f"fuzz-batch-{name}", *args, time_limit_s=limit_s)
    elif workers.can_serve():
        job = workers.start_served(
            f"fuzz-batch-{name}", *args, preload=SERVER_PRELOAD, time_limit_s=limit_s
        )
    else:
        progress, over_budget = _budget_progress(limit_s)
        try:
            return _simulate_batch_task(pl, scenes, horizon, reached, progress)
        except over_budget as exc:
            raise OverTime(name, limit_s, reached.value) from exc
        except KeyboardInterrupt:
            raise
        except Exception as exc:
            raise _Raised(type(exc).__name__, _one_line(exc).partition(": ")[2]) from exc
    try:
        return job.result()
    except workers.OverTime as exc:
        raise OverTime(name, limit_s, reached.value) from exc
    except workers.WorkerError as exc:
        raise _Raised(exc.kind, exc.message) from exc
    except workers.WorkerLost as exc:
        raise _Raised(type(exc).__name__, str(exc)) from exc
    except BaseException:
        workers.stop([job])
        raise


def batch_runs(
    name: str, pl: Plant, scenes: Sequence[Scene], horizon: float, budget_s: float
) -> list[PlantRun]:
    """Plant ``pl``'s runs of ``scenes`` (one structure, each accepted by the plant) over
    ``horizon`` s in one batch, each scene's run within ``budget_s`` s (the batch within
    ``len(scenes) × budget_s``): one :class:`PlantRun` per scene, in order (module docstring).
    Only an interrupt escapes."""
    scenes = list(scenes)
    count = len(scenes)
    if not count:
        return []
    limit = budget_s * count
    t0 = time.perf_counter()
    try:
        out = run_batch_limited(name, pl, scenes, horizon, limit)
    except OverTime as exc:
        share = (time.perf_counter() - t0) / count
        return [PlantRun(name, None, share, exc.limit_s, "", str(exc), exc.reached_s)] * count
    except _Raised as exc:
        share = (time.perf_counter() - t0) / count
        return [PlantRun(name, None, share, None, exc.kind, str(exc))] * count
    share = (time.perf_counter() - t0) / count
    if not isinstance(out, list) or len(out) != count:
        got = f"{len(out)} items" if isinstance(out, list) else type(out).__name__
        why = f"broke the plant contract: simulate_batch returned {got} for {count} scenes"
        return [PlantRun(name, None, share, None, ContractError.__name__, why)] * count
    return [returned_run(name, tr, s, horizon, share) for tr, s in zip(out, scenes, strict=True)]


def batch_plant_task(
    seed: int, indices: Sequence[int], p: Plant | str, horizon: float, budget_s: float
) -> dict[str, Any]:
    """An executor's task: plant ``p``'s runs of the campaign scenes ``indices`` of ``seed`` in one
    batch (scenes the caller prepared and found of one structure, each accepted by the plant).
    Back: ``runs``, one :class:`PlantRun` per index, in order."""
    name, pl = plant_name(p), resolve_plant(p)
    scenes: list[Scene] = []
    refusals: dict[int, str] = {}
    for k, index in enumerate(indices):
        scene, refused, chosen = prepare(draw_scene_dict(seed, index, horizon), [pl], horizon)
        if scene is None or not chosen:  # the caller checked; a worker's registry may differ
            refusals[k] = next(iter(refused.values()), "refused")
        else:
            scenes.append(scene)
    if refusals:  # not one structure the plant accepts after all: no batch
        why = "; ".join(f"scenes[{k}]: {r}" for k, r in refusals.items())
        return {"runs": [PlantRun(name, None, 0.0, None, "ValueError", why)] * len(indices)}
    return {"runs": batch_runs(name, pl, scenes, horizon, budget_s)}


__all__ = [
    "batch_plant_task",
    "batch_runs",
    "run_batch_limited",
    "structure_key",
]
