"""What the benchmarks share: the scene they time and how they time it.

:func:`chain_scene` builds the controlled scene of n masses that :mod:`validation.bench.command`,
:mod:`validation.bench.goals` and :mod:`validation.bench.fast_bench` time. Both live here, below the
three benchmark modules, so that none of them imports another (the import graph has no cycles,
``tests/cross/test_layers.py``).

**The clock is the thread's CPU time** (:func:`time.thread_time_ns`), not the wall clock. What is
timed in-process (a compiled evaluation, ``mj_forward``, ``mj_step``) runs in the calling thread
alone (one BLAS thread, no pool), so its thread CPU time is its cost, and it stays so beside other
work. The wall clock also counts the time the thread waits while the scheduler runs another
process on its core, and where those preemptions land follows the rhythm of the alternating
batches, not the work: a ratio of wall times beside a CPU-bound job measures the scheduler (the
figures: ``docs/performance.md``, On a busy machine). :class:`Batch` keeps both clocks and the
involuntary context switches, so the share of a CPU the thread had is printed beside every goal.
"""

from __future__ import annotations

import resource
import statistics
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from analytic.scene import Scene, random_scenes

CALIBRATE_S = 1e-3
"""Thread CPU time a calibration run must reach before its per-call cost is trusted, s."""

BATCH_S = 5e-3
"""Thread CPU time of one batch of :func:`interleaved`, s: long enough that the two clock reads
(~0.1 µs) are negligible, short enough for many rounds in a second."""


def chain_scene(n: int, seed: int = 0) -> Scene:
    """A controlled scene with n masses on a generic rod (not through C), every axis of ω and every
    mass tracked: :func:`analytic.scene.random_scenes.chain_scene` (the one random-scene generator)."""
    return random_scenes.chain_scene(n, seed)


@dataclass(frozen=True)
class Batch:
    """One timed batch of ``calls`` calls: thread CPU time and wall time, s, and the involuntary
    context switches of the thread during it (the scheduler ran something else on its core)."""

    calls: int
    cpu_s: float
    wall_s: float
    involuntary: int

    @property
    def per_call_s(self) -> float:
        """Thread CPU seconds per call."""
        return self.cpu_s / self.calls

    @property
    def cpu_share(self) -> float:
        """Thread CPU time / wall time (1: the thread had its core to itself)."""
        return self.cpu_s / self.wall_s if self.wall_s > 0 else 1.0


def _switches() -> int:
    return resource.getrusage(resource.RUSAGE_THREAD).ru_nivcsw


def time_batch(fn: Callable[[], Any], calls: int) -> Batch:
    """``calls`` calls of ``fn()`` as one :class:`Batch`."""
    s0 = _switches()
    c0 = time.thread_time_ns()
    w0 = time.perf_counter_ns()
    for _ in range(calls):
        fn()
    w1 = time.perf_counter_ns()
    c1 = time.thread_time_ns()
    return Batch(calls, (c1 - c0) * 1e-9, (w1 - w0) * 1e-9, _switches() - s0)


def calls_per_batch(fn: Callable[[], Any], batch_s: float = BATCH_S) -> int:
    """How many calls of ``fn()`` take about ``batch_s`` of thread CPU time (doubling a run until it
    takes :data:`CALIBRATE_S`, then scaling; at least 1)."""
    calls = 1
    while True:
        b = time_batch(fn, calls)
        if b.cpu_s >= CALIBRATE_S:
            return max(1, round(batch_s * calls / b.cpu_s))
        calls *= 2


def interleaved(
    fns: Mapping[str, Callable[[], Any]], rounds: int = 21, batch_s: float = BATCH_S
) -> dict[str, list[Batch]]:
    """``rounds`` batches of each function, alternating: in each round every function once, in the
    given order in even rounds and reversed in odd ones (neither side always follows the other).
    Each function is called once first (caches, compilation), then sized to ``batch_s`` of thread
    CPU time. Returns each function's batches in round order."""
    for fn in fns.values():
        fn()
    calls = {k: calls_per_batch(fn, batch_s) for k, fn in fns.items()}
    out: dict[str, list[Batch]] = {k: [] for k in fns}
    names = list(fns)
    for r in range(rounds):
        for k in names if r % 2 == 0 else reversed(names):
            out[k].append(time_batch(fns[k], calls[k]))
    return out


def median_per_call(batches: list[Batch]) -> float:
    """Median thread CPU seconds per call over the batches."""
    return statistics.median(b.per_call_s for b in batches)


def median_share(samples: Mapping[str, list[Batch]]) -> float:
    """Median share of a CPU over every batch of every function (see :attr:`Batch.cpu_share`)."""
    return statistics.median(b.cpu_share for v in samples.values() for b in v)


def time_call(fn: Callable[[], Any], repeats: int = 7, number: int | None = None) -> float:
    """Median thread CPU seconds per call of ``fn()`` over ``repeats`` batches of ``number`` calls
    (by default sized to 50 ms each)."""
    fn()
    if number is None:
        number = calls_per_batch(fn, 0.05)
    return statistics.median(time_batch(fn, number).per_call_s for _ in range(repeats))


class CpuMeter:
    """The thread CPU time of a run that reports only its wall time.

    A plant's ``info["wall_time_s"]`` is the wall of its integration alone (the setup of the call
    excluded). Passed as the run's ``progress`` callback, the meter reads both clocks at every
    report (each output sample or simulated second), so it knows the share of a CPU the thread had
    *during the integration*; the run's CPU time is its wall times that share. Usage::

        meter = CpuMeter()
        with meter:
            tr = plant.simulate(scene, settings, t_end=t_end, progress=meter)
        cpu_s = meter.cpu_of(tr.info["wall_time_s"])

    With fewer than two reports (a very short run) the share over the whole ``with`` block is used.
    """

    def __init__(self) -> None:
        self._marks: list[tuple[int, int]] = []
        self._outer: tuple[int, int, int, int] | None = None

    def __call__(self, _t: float) -> None:
        self._marks.append((time.perf_counter_ns(), time.thread_time_ns()))

    def __enter__(self) -> CpuMeter:
        self._marks.clear()
        self._start = (time.perf_counter_ns(), time.thread_time_ns())
        return self

    def __exit__(self, *exc: object) -> None:
        w1, c1 = time.perf_counter_ns(), time.thread_time_ns()
        self._outer = (*self._start, w1, c1)

    @property
    def share(self) -> float:
        """Thread CPU time / wall time over the integration (at most 1)."""
        if len(self._marks) >= 2 and self._marks[-1][0] > self._marks[0][0]:
            (w0, c0), (w1, c1) = self._marks[0], self._marks[-1]
        elif self._outer is not None and self._outer[2] > self._outer[0]:
            w0, c0, w1, c1 = self._outer
        else:
            return 1.0
        return min(1.0, (c1 - c0) / (w1 - w0))

    def cpu_of(self, wall_s: float) -> float:
        """The CPU time of a span of ``wall_s`` wall seconds inside the run, s."""
        return wall_s * self.share
