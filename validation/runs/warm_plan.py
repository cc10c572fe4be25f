"""The plan of a warm-up: which task waits for which, the order the workers take them in, and
the announced estimate of its wall time.

:func:`needs` is what must be compiled before a task starts; whenever a worker is free it takes
the ready task of highest :func:`priority` (the longest chain of costs it starts, critical path
first; :func:`order`). :func:`schedule` replays that rule with the per-job costs of
:data:`COST_S` as durations, and :func:`estimate_s` is its end plus a worker's start: the figure
the warm-up announces, never a limit (a busy machine takes longer). The costs are measured figures
(``docs/performance.md``, "Warm-up estimate"); they change the announcement only.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from validation.runs.warm_jobs import KERNELS, Job, Task

COST_S: dict[Job, float] = {
    Job.SYSTEM: 3.1,
    Job.SOLVE: 2.6,
    Job.RHS: 1.7,
    Job.MUJOCO_STAGE: 2.4,
    Job.PINOCCHIO_STAGE: 3.7,
    Job.PLANT: 0.2,
}
"""Wall time of each job on an empty cache with two of them side by side, s (how they were
measured: ``docs/performance.md``, "Warm-up estimate"); used only for the announced estimate."""

POOL_START_S = 1.0
"""A worker's start (numba and the kernel's modules imported), s, measured as :data:`COST_S`."""

HALVES = (Job.SYSTEM, Job.SOLVE)
"""The analytic kernel's two halves, which the Pinocchio stage waits for."""


def needs(task: Task, tasks: Sequence[Task]) -> set[tuple]:
    """The keys among ``tasks`` that must be done before ``task`` starts: a plant's interval waits
    for its kernels (else it would compile them again); the Pinocchio stage for the kernel's
    halves (its dynamics binds their addresses). Everything else calls the halves by address and
    compiles without them."""
    if task.job is Job.PLANT:
        own = KERNELS[task.engine]
        return {t.key for t in tasks if t.job is not Job.PLANT and t.job in own}
    if task.job is Job.PINOCCHIO_STAGE:
        return {t.key for t in tasks if t.job in HALVES}
    return set()


def estimate_s(tasks: Sequence[Task], workers: int) -> float:
    """The announced wall time of a warm-up, s: :func:`schedule` of the measured :data:`COST_S`
    on ``workers`` processes, plus a worker's start."""
    return POOL_START_S + max((end for _t, _start, end in schedule(tasks, workers)), default=0.0)


def schedule(tasks: Sequence[Task], workers: int) -> list[tuple[Task, float, float]]:
    """``(task, start, end)`` in s of each task as the warm-up's pool runs them
    (:func:`validation.runs.warmup.warm_up`), with the measured :data:`COST_S` as durations:
    whenever a worker is free, it takes the ready task of highest :func:`priority` (or waits for
    the next one to finish)."""
    waiting = order(tasks)
    free = [0.0] * max(1, workers)
    ends: dict[tuple, float] = {}
    out = []
    while waiting:
        k = free.index(min(free))
        now = free[k]
        ready = [t for t in waiting if all(ends.get(x, math.inf) <= now for x in needs(t, tasks))]
        if not ready:  # idle until the next task ends
            free[k] = min(e for e in ends.values() if e > now)
            continue
        t = ready[0]
        waiting.remove(t)
        free[k] = ends[t.key] = now + COST_S[t.job]
        out.append((t, now, free[k]))
    return out


def priority(task: Task, tasks: Sequence[Task]) -> float:
    """The longest chain of measured costs from ``task``'s start to the end of what waits for it
    (critical-path first: the kernel's halves, which the Pinocchio stage and every plant wait
    for, go before a longer job that nothing waits for)."""
    after = [priority(u, tasks) for u in tasks if task.key in needs(u, tasks)]
    return COST_S[task.job] + max(after, default=0.0)


def order(tasks: Sequence[Task]) -> list[Task]:
    """``tasks`` by decreasing :func:`priority` (a task always after what it needs)."""
    return sorted(tasks, key=lambda t: -priority(t, tasks))
