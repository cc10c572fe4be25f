"""A campaign's scenes grouped into batches for the plants that run batches natively.

The campaign starts scene ``i`` as one task per plant (:func:`validation.studies.fuzz.campaign.
submit_scene`). For a plant whose :attr:`analytic.plant.Plant.batched` is True, the scenes of one
**block** of :data:`BATCH_BLOCK` consecutive indices (``[kB, (k+1)B)``, cut at the budget) that
share one structure (:func:`validation.studies.fuzz.batch_runs.structure_key`: ``n`` and the
effects) and that the plant accepts are one task instead, one ``simulate_batch`` call
(:func:`validation.studies.fuzz.batch_runs.batch_plant_task`), submitted when the block's first
scene is started. Every other plant's task of a scene is submitted when that scene is started,
exactly as without batches.

What a scene then waits on for a batched plant is a :class:`BatchShare`, its place in its batch's
future, which the scene's :class:`~validation.studies.fuzz.campaign.Pending` takes like any
plant's future (``result()["run"]`` is the scene's own
:class:`~validation.studies.fuzz.judge.PlantRun`); the comparison, findings, shrinking (one
candidate at a time, on every plant's single-run path), the records and resume are the campaign's
own. Blocks are fixed by index, so a seed's batches are the same on every executor; a resumed
campaign leaves the scenes already judged out of its batches (a native batch's worlds do not
depend on each other, so a scene's run does not depend on its batch).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from concurrent.futures import Executor, Future
from dataclasses import dataclass, field
from typing import Any

from analytic.plant import Plant
from validation.studies.fuzz.batch_runs import batch_plant_task, structure_key
from validation.studies.fuzz.campaign_records import load_scene_record
from validation.studies.fuzz.directory import CampaignDir
from validation.studies.fuzz.judge import plant_name, prepare, resolve_plant
from validation.studies.fuzz.records import FuzzConfig, SceneRecord
from validation.studies.fuzz.space import draw_scene_dict

BATCH_BLOCK = 16
"""Consecutive scene indices whose scenes of one structure share one batch on a batched plant:
the campaign's space draws many structures (``n`` from 0 to 50, effects on and off), so a block
of 16 holds a few scenes of the commonest ones; a larger block makes bigger batches and makes a
scene wait longer for its batch's other scenes."""


def batched_plants(plants: Sequence[Plant | str]) -> frozenset[str]:
    """The names of the ``plants`` whose ``batched`` is True (an unknown name: ``ValueError``)."""
    return frozenset(plant_name(p) for p in plants if resolve_plant(p).batched)


@dataclass
class _Batch:
    """One batch's future and which of its places were cancelled."""

    future: Future
    size: int
    cancelled: set[int] = field(default_factory=set)


@dataclass
class BatchShare:
    """Scene ``position`` of a batch, as the future of that scene's run on the batch's plant."""

    batch: _Batch
    position: int

    def result(self, timeout: float | None = None) -> dict[str, Any]:
        return {"run": self.batch.future.result(timeout)["runs"][self.position]}

    def cancel(self) -> bool:
        """Drop this scene's place; the batch is cancelled when every place is (if not started)."""
        self.batch.cancelled.add(self.position)
        if len(self.batch.cancelled) == self.batch.size:
            return self.batch.future.cancel()
        return False


@dataclass
class _Planned:
    """A scene of a planned block: its prepared scene, refusals, runnable plants and the shares of
    its batched plants."""

    data: dict[str, Any]
    scene: Any
    refused: dict[str, str]
    chosen: list[tuple[str, Plant]]
    shares: dict[str, BatchShare]


class CampaignBatches:
    """Scenes started for the campaign with batches for its batched plants (module docstring).

    ``start(index)`` returns the scene's :class:`SceneRecord` when it was judged before, else its
    ``Pending`` (plants' futures in the plants' order); ``close()`` cancels the batches no scene
    waits on any more.
    """

    def __init__(
        self,
        cd: CampaignDir,
        cfg: FuzzConfig,
        plants: Sequence[Plant | str],
        ex: Executor,
        budget: int | None,
        batched: frozenset[str],
    ):
        self._cd, self._cfg, self._plants, self._ex = cd, cfg, tuple(plants), ex
        self._budget, self._batched = budget, batched
        self._blocks: dict[int, dict[int, SceneRecord | _Planned]] = {}
        self._batches: list[_Batch] = []

    def start(self, index: int, pending: Any, task: Any) -> Any:
        """Scene ``index``: its record, or its ``pending(scene, horizon, refused, futures)`` with
        each non-batched plant's ``task(seed, index, plant, horizon, limit_s)`` submitted now."""
        block = index // BATCH_BLOCK
        if block not in self._blocks:
            self._blocks[block] = self._plan(block)
        got = self._blocks[block].pop(index, None)
        if not self._blocks[block]:
            del self._blocks[block]
        if got is None:  # past the budget the block was cut at: planned on its own
            got = self._plan_one(index)
        if isinstance(got, SceneRecord):
            return got
        cfg = self._cfg
        if got.scene is None:
            return pending(None, cfg.horizon, got.refused, [])
        by_name = {plant_name(p): p for p in self._plants}
        futures = [
            got.shares[name]
            if name in got.shares
            else self._ex.submit(
                task, cfg.seed, index, by_name[name], cfg.horizon, cfg.time_limit_s
            )
            for name, _ in got.chosen
        ]
        return pending(got.scene, cfg.horizon, got.refused, futures)

    def close(self) -> None:
        """Cancel every batch not started (its scenes never taken: the campaign ended first)."""
        for b in self._batches:
            b.future.cancel()

    def _plan_one(self, index: int) -> SceneRecord | _Planned:
        rec = load_scene_record(self._cd, self._cfg, index)
        if rec is not None:
            return rec
        data = draw_scene_dict(self._cfg.seed, index, self._cfg.horizon)
        scene, refused, chosen = prepare(data, self._plants, self._cfg.horizon)
        return _Planned(data, scene, refused, chosen, {})

    def _plan(self, block: int) -> dict[int, SceneRecord | _Planned]:
        """Every scene of ``block`` prepared, and one batch submitted per batched plant and
        structure."""
        first = block * BATCH_BLOCK
        last = first + BATCH_BLOCK
        if self._budget is not None:
            last = min(last, self._budget)
        planned = {i: self._plan_one(i) for i in range(first, last)}
        groups: dict[tuple[str, Any], list[int]] = defaultdict(list)
        for i, got in planned.items():
            if isinstance(got, _Planned) and got.scene is not None:
                for name, _pl in got.chosen:
                    if name in self._batched:
                        groups[name, structure_key(got.scene)].append(i)
        by_name = {plant_name(p): p for p in self._plants}
        cfg = self._cfg
        for (name, _key), indices in groups.items():
            future = self._ex.submit(
                batch_plant_task, cfg.seed, indices, by_name[name], cfg.horizon, cfg.time_limit_s
            )
            batch = _Batch(future, len(indices))
            self._batches.append(batch)
            for k, i in enumerate(indices):
                planned[i].shares[name] = BatchShare(batch, k)
        return planned


__all__ = ["BATCH_BLOCK", "BatchShare", "CampaignBatches", "batched_plants"]
