"""Batched plants for the tests of the batched entry's callers: the fake batched plugin
(``tests/support/plugin_batched``) and its broken variants.

In a module of their own (not the test files), as :mod:`tests.support.fuzz_plants`: a campaign's
runs may be made in children of a fork server, which import the module of a plant's class."""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from tests.support.fuzz_plants import SLEEP_S
from tests.support.plugin_batched.tumble_plugin_batched import BatchedEchoPlant


class LoopedEchoPlant(BatchedEchoPlant):
    """The same plant with ``batched = False``: callers take its per-scene path."""

    batched = False


class RaisingBatchPlant(BatchedEchoPlant):
    """Its batches raise; its single runs are right (a shrink candidate runs alone)."""

    engine = "raising_batch"

    def _simulate_batch(self, scenes, settings, t_end, progress):
        raise RuntimeError(f"lost its device with {len(scenes)} worlds")


class BrokenFirstPlant(BatchedEchoPlant):
    """Its batches return the first scene's trajectory with a column of ``q`` missing: that scene's
    run breaks the plant contract, the others' are right."""

    engine = "broken_first"

    def _simulate_batch(self, scenes, settings, t_end, progress):
        out = super()._simulate_batch(scenes, settings, t_end, progress)
        out[0] = dataclasses.replace(out[0], q=np.array(out[0].q)[:, :-1])
        return out


class ShortBatchPlant(BatchedEchoPlant):
    """Its batches return one trajectory fewer than scenes (none at all for one scene)."""

    engine = "short_batch"

    def _simulate_batch(self, scenes, settings, t_end, progress):
        return super()._simulate_batch(scenes, settings, t_end, progress)[1:]


class SleepyBatchPlant(BatchedEchoPlant):
    """Its batches sleep ``SLEEP_S`` s without reporting progress before they run."""

    engine = "sleepy_batch"

    def _simulate_batch(self, scenes, settings, t_end, progress):
        time.sleep(SLEEP_S)
        return super()._simulate_batch(scenes, settings, t_end, progress)


__all__ = [
    "BatchedEchoPlant",
    "BrokenFirstPlant",
    "LoopedEchoPlant",
    "RaisingBatchPlant",
    "ShortBatchPlant",
    "SleepyBatchPlant",
]
