"""Importing this module makes every plant ready to run in this process, for every solve
(:func:`validation.runs.warm_plants.warm_all`: kernels loaded, each plant run once over one output
interval of a built-in scene).

It exists for a fork server's preload (:func:`validation.runs.workers.start_served`): a fork server
only imports modules, and every child it forks inherits what they loaded, so each child's run
starts ready instead of loading its kernels from numba's cache again (about 0.5 s per plant and
run) and paying its plant's first use (:mod:`validation.runs.warm_plants`). Three plants x three
solves from a warm cache take about 1.8 s, once per fork server.

Import it only on purpose: it does its work at import.
"""

from __future__ import annotations

from validation.runs.warm_plants import warm_all

LOADED = warm_all()
"""What the import did: one :class:`validation.runs.warmup.StageTime` per job."""
