"""Compile the plants' numba kernels ahead of a run: ``tumble warmup``, and a first ``tumble validate``.

numba compiles each kernel on its first call and keeps the machine code in its on-disk cache
(``__pycache__`` beside the sources, or ``$NUMBA_CACHE_DIR``); later processes load it in well under
a second. A first run on a machine pays the compile once. :func:`warm_up` pays it up front and says
so, one line per kernel:

1. **Is it needed?** A stamp file beside numba's cache (:data:`WARM_STAMP`) lists the
   :func:`warm_keys` of every (plant, weighting) whose kernels a warm-up finished. A run whose keys
   are all listed starts at once, silently, without importing numba. Any change of the sources,
   numba, llvmlite, Python, the CPU or a ``NUMBA_*`` setting changes the keys.
2. **The kernels** (:class:`validation.runs.warm_jobs.Job`), each compiled (or loaded from numba's
   cache) in a worker process of a ``concurrent.futures.ProcessPoolExecutor``, side by side on the
   free CPUs: the kernel's two halves (:mod:`analytic.kernel.halves`), and what calls them by
   address and so compiles without them (:mod:`analytic.runtime.abi`): the analytic plant's
   compiled right-hand side, the MuJoCo plant's stage and native callback, the Pinocchio stage.
   numba holds the GIL while it compiles, so threads would not overlap; processes do, and each
   leaves its result in the on-disk cache.
3. **Then one output interval of each plant**, also in the pool: it finds the kernels on disk and
   compiles whatever else its default settings call.

This module decides whether a warm-up is needed (the stamp), which tasks a set of scenes and
plants needs (:func:`tasks_for`), and runs them in the pool, in the order of
:mod:`validation.runs.warm_plan`, whose :func:`~validation.runs.warm_plan.estimate_s` is the
announced wall time (a busy machine takes longer); each task is
:func:`validation.runs.warm_jobs.run_task`.

A failure while warming up is never fatal: it is reported on its line, and the plant's own run
compiles what is missing and reports its own error. Without a writable cache directory there is
nothing to keep: one line says so and every run compiles its kernels.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import multiprocessing
import os
import platform
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Executor, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

from validation.runs.atomic import write_text
from validation.runs.lifetime import pool_initializer
from validation.runs.warm_jobs import ENGINES, KERNELS, Job, StageTime, Task, run_task
from validation.runs.warm_plan import estimate_s, needs, order
from validation.runs.workers import flush_std_streams

if TYPE_CHECKING:
    from analytic.scene import Scene


@dataclass(frozen=True)
class WarmupResult:
    """What :func:`warm_up` did.

    Attributes:
        stages: each job, in the order it finished (empty: nothing to do).
        seconds: wall time of the whole warm-up, s.
        workers: worker processes used.
        cached: whether numba keeps the result on disk (False: every process compiles).
    """

    stages: tuple[StageTime, ...] = ()
    seconds: float = 0.0
    workers: int = 0
    cached: bool = True


# ----------------------------------------------------------------------------------------------
# Is a warm-up needed? (our own stamp: nothing of numba is read)
# ----------------------------------------------------------------------------------------------

WARM_STAMP = "tumble-kernels-warm.json"
"""A file beside numba's cache of the kernel (:func:`analytic.runtime.cache_dir.kernel_cache_dir`)
listing the :func:`warm_key` values whose kernels a warm-up compiled. Should the stamp outlive the
cache (a deleted ``__pycache__``), the plants compile what is missing themselves, unannounced."""

STAMP_KEYS_KEPT = 32  # plants x weightings x interpreters sharing one tree


def _cpu_identity() -> str:
    """What tells this machine's CPU from another for compiled code: the model and feature flags
    from ``/proc/cpuinfo``, else :func:`platform.processor`."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            lines = f.read().split("\n\n", 1)[0].splitlines()
        wanted = ("model name", "flags", "Features", "CPU implementer", "CPU part")
        return "\n".join(line for line in lines if line.split(":", 1)[0].strip() in wanted)
    except OSError:
        return f"{platform.machine()} {platform.processor()}"


def _source_roots() -> list[Path]:
    """The directories of the packages that hold compiled code."""
    import analytic
    import mj_bridge

    return [Path(pkg.__file__).resolve().parent for pkg in (analytic, mj_bridge)]


def _environment_digest() -> str:
    """SHA-256 of every source of :mod:`analytic` and :mod:`mj_bridge`, the versions of numba,
    llvmlite and Python, the CPU and the ``NUMBA_*`` settings."""
    h = hashlib.sha256()
    for root in _source_roots():
        for path in sorted(root.rglob("*.py")):
            h.update(str(path.relative_to(root.parent)).encode())
            h.update(path.read_bytes())
    for dist in ("numba", "llvmlite"):
        try:
            h.update(f"{dist} {metadata.version(dist)}".encode())
        except metadata.PackageNotFoundError:
            h.update(f"{dist} absent".encode())
    h.update(f"{sys.version} {platform.machine()}".encode())
    h.update(_cpu_identity().encode())
    h.update(repr(sorted((k, v) for k, v in os.environ.items() if k.startswith("NUMBA_"))).encode())
    return h.hexdigest()


def warm_keys(engines: Sequence[str], scene: Scene) -> list[str]:
    """One key per plant for ``scene``'s weighting (which selects the compiled solve), under
    :func:`_environment_digest`."""
    base = _environment_digest()
    weighting = str(scene.control.weighting)
    return [hashlib.sha256(f"{base} {e} {weighting}".encode()).hexdigest() for e in engines]


def _stamp_path() -> Path | None:
    from analytic.runtime.cache_dir import kernel_cache_dir

    where = kernel_cache_dir()
    return where / WARM_STAMP if where is not None else None


def _stamped_keys() -> list[str]:
    from analytic.runtime.safe_files import read_regular  # never blocks (a FIFO there)

    path = _stamp_path()
    try:
        keys = json.loads(read_regular(path, 1 << 20))["warm_keys"] if path else []
    except (OSError, ValueError, KeyError, TypeError):
        return []
    return [k for k in keys if isinstance(k, str)] if isinstance(keys, list) else []


def is_stamped_warm(keys: Sequence[str]) -> bool:
    """Whether a warm-up compiled the kernels of every key before."""
    stamped = set(_stamped_keys())
    return all(k in stamped for k in keys)


def stamp_warm(keys: Sequence[str]) -> None:
    """Record ``keys`` as warm (atomically; a stamp that cannot be written is no error), and the
    hashes of numba's cache files as they are now (:func:`analytic.runtime.cache_check.record`)."""
    from analytic.runtime import cache_check

    path = _stamp_path()
    if path is None:
        return
    cache_check.record()  # the kernels on disk now are the ones numba wrote: their hashes kept
    kept = [k for k in _stamped_keys() if k not in keys]
    kept = [*kept, *keys][-STAMP_KEYS_KEPT:]
    try:
        write_text(path, json.dumps({"warm_keys": kept}, indent=1) + "\n")
    except OSError:
        pass


# ----------------------------------------------------------------------------------------------
# The jobs
# ----------------------------------------------------------------------------------------------


def compiled_solver(scene: Scene) -> int | None:
    """The solve (an :class:`analytic.kernel.entry.Solver` value) the scene's compiled kernel uses,
    without compiling anything; None when there is no compiled kernel (numba absent)."""
    from analytic import fast

    if not fast.available():
        return None
    fm = fast.FastModel(scene)
    return int(fm.solver) if fm.compiled else None


def tasks_for(
    scenes_engines: Sequence[tuple[Scene, str]],
) -> tuple[list[Task], list[Task]]:
    """``(kernels, plants)``: the kernels each plant needs for its scene, then one output interval
    of each plant per solve, each once (a scene the compiled kernel does not serve adds none)."""
    kernels: list[Task] = []
    plants: list[Task] = []
    for scene, engine in scenes_engines:
        solver = compiled_solver(scene)
        if solver is not None:
            kernels += [Task(job, solver, scene) for job in KERNELS[engine]]
            plants.append(Task(Job.PLANT, solver, scene, engine))
    return _unique(kernels), _unique(plants)


def _unique(tasks: Sequence[Task]) -> list[Task]:
    seen: dict[tuple, Task] = {}
    for t in tasks:
        seen.setdefault(t.key, t)
    return list(seen.values())


# ----------------------------------------------------------------------------------------------
# Running them
# ----------------------------------------------------------------------------------------------


def free_cpus() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def _pool(workers: int, fork: bool | None = None) -> ProcessPoolExecutor:
    """Worker processes, forked when that is safe (Linux, no other thread in this process: they
    inherit what is imported here), else spawned (``fork`` forces either); each ends when this
    process does (:func:`validation.runs.lifetime.pool_initializer`)."""
    if fork is None:
        methods = multiprocessing.get_all_start_methods()
        fork = sys.platform == "linux" and "fork" in methods and threading.active_count() == 1
    if fork:
        flush_std_streams()  # nothing buffered here is written twice
    context = multiprocessing.get_context("fork" if fork else "spawn")
    return ProcessPoolExecutor(
        max_workers=workers,
        mp_context=context,
        initializer=pool_initializer,
        initargs=(os.getpid(),),
    )


def _run_all(
    pool: Executor, workers: int, tasks: Sequence[Task], report: Callable[[StageTime], None]
) -> None:
    """Run ``tasks`` (each :func:`~validation.runs.warm_jobs.run_task`) on the ``workers`` of
    ``pool``: whenever one is free, the task of highest
    :func:`~validation.runs.warm_plan.priority` whose :func:`~validation.runs.warm_plan.needs` are
    done; each reported as it finishes."""
    waiting = order(tasks)
    blockers = {t.key: needs(t, tasks) for t in tasks}
    running: dict[Any, Task] = {}
    done: set[tuple] = set()
    while waiting or running:
        ready = [t for t in waiting if blockers[t.key] <= done]
        for t in ready[: max(0, workers - len(running))]:
            waiting.remove(t)
            running[pool.submit(run_task, t)] = t
        finished, _ = wait(running, return_when=FIRST_COMPLETED)
        for fut in finished:
            task = running.pop(fut)
            done.add(task.key)
            try:
                st = fut.result()
            except Exception as exc:  # the worker died (a crash in compiled code, killed)
                st = StageTime(task.title, 0.0, f"{type(exc).__name__}: {exc}".splitlines()[0])
            report(st)


def cache_writable() -> bool:
    """Whether numba keeps the compiled kernels on disk here (a writable cache directory)."""
    from analytic.runtime import cache_check
    from analytic.runtime.cache_dir import kernel_cache_dir

    mode = cache_check.disk_cache_mode()
    return kernel_cache_dir() is not None and mode is not cache_check.Mode.NONE


_warmed_here: set[str] = set()
"""Keys this process warmed up: what the cache check deleted is compiled again for them."""


def warm_up(
    scenes: Sequence[Scene],
    plants: Sequence[Any],
    progress: Callable[[str], None] | None = None,
    force: bool = False,
    workers: int | None = None,
) -> WarmupResult:
    """Compile what ``plants`` need for each of ``scenes`` unless a warm-up did before.

    Args:
        scenes: the resolved scenes the runs will use (their weighting selects the solve).
        plants: engine names or :class:`~analytic.trajectory.Engine` members; each must run
            every scene (the plants' ``check_scene``).
        progress: receives one line per event: the announcement (how many kernels, how long as
            measured), one line per job with its wall time, the total. Nothing is sent when
            already warm.
        force: run the jobs even when stamped warm (each then loads from numba's cache).
        workers: worker processes (default: the CPUs free to this process, at most one per job).

    Returns:
        a :class:`WarmupResult` (no stages: nothing was needed).
    """
    from analytic.runtime import cache_check

    say = progress or (lambda _line: None)
    names = {str(getattr(p, "value", p)) for p in plants}
    engines = [e for e in ENGINES if e in names]
    t0 = time.perf_counter()
    cache_check.ensure_checked()  # numba's cache files against their hashes (no numba import)
    keys = [k for scene in scenes for k in warm_keys(engines, scene)]
    rechecked = cache_check.removed_any() and not _warmed_here.issuperset(keys)  # not redone
    if not force and is_stamped_warm(keys) and not rechecked:
        return WarmupResult()
    kernels, plant_tasks = tasks_for([(scene, e) for scene in scenes for e in engines])
    if not kernels:
        return WarmupResult()
    if not cache_writable():
        say(
            "numba has no writable cache directory here (set NUMBA_CACHE_DIR): every run compiles "
            f"its kernels (~{estimate_s([*kernels, *plant_tasks], 1):.0f} s)"
        )
        return WarmupResult(cached=False)
    n = max(1, min(workers or free_cpus(), len(kernels)))
    say(
        f"{'compiling (or loading)' if force else 'compiling'} {len(kernels)} numba kernels once "
        f"per machine (~{estimate_s([*kernels, *plant_tasks], n):.0f} s with {n} worker"
        f"{'s' if n > 1 else ''}, as measured on 2 cores; later runs load them from numba's cache):"
    )
    stages: list[StageTime] = []

    def report(st: StageTime) -> None:
        stages.append(st)
        tail = f" (failed: {st.error}; the run compiles it instead)" if st.error else ""
        say(f"  {st.title}: {st.seconds:.1f} s{tail}")

    try:
        with _pool(n) as pool:
            _run_all(pool, n, [*kernels, *plant_tasks], report)
    except BrokenProcessPool as exc:  # a worker died: what is left compiles in the run
        report(StageTime("the warm-up's worker processes", 0.0, f"BrokenProcessPool: {exc}"))
    total = time.perf_counter() - t0
    say(f"  kernels ready in {total:.1f} s")
    if not any(st.error for st in stages):
        stamp_warm(keys)
        _warmed_here.update(keys)
    return WarmupResult(tuple(stages), total, n, True)


@contextlib.contextmanager
def warming(
    scene: Scene, plants: Sequence[Any], progress: Callable[[str], None] | None = None
) -> Iterator[WarmupResult]:
    """:func:`warm_up` for one scene, then the body (what ``tumble validate`` wraps its run in)."""
    yield warm_up([scene], plants, progress)


def builtin_scenes() -> list[Scene]:
    """Every built-in scene (what ``tumble warmup`` without a scene compiles for)."""
    from analytic.scene import load_scene  # the built-in names' own loader (runs sits below scenes)
    from analytic.scene.builtin import builtin_scene_names

    return [load_scene(name) for name in builtin_scene_names()]


def supported(scene: Scene, engine: str) -> bool:
    """Whether ``engine``'s plant can run ``scene`` (its ``check_scene`` accepts it)."""
    from mj_bridge.plants import plant

    try:
        plant(engine).check_scene(scene)
    except ValueError:
        return False
    return True


def warm_up_command(
    scenes: Sequence[Scene], engines: Sequence[str], out: Callable[[str], None] = print
) -> bool:
    """``tumble warmup``: every kernel ``engines`` need for ``scenes`` (each plant with the scenes
    it can run), one line per job with its time, compiled even when stamped warm (a job then loads
    from the cache in a fraction of a second). Returns whether every job worked."""
    pairs = [(scene, e) for scene in scenes for e in engines if supported(scene, e)]
    by_plant: dict[str, list[Scene]] = {}
    for scene, e in pairs:
        by_plant.setdefault(e, []).append(scene)
    # one warm-up per set of plants that run the same scenes (usually one for all)
    groups: dict[tuple[str, ...], list[str]] = {}
    for e, its in by_plant.items():
        groups.setdefault(tuple(s.name for s in its), []).append(e)
    ok = True
    for names, group in groups.items():
        chosen = [s for s in scenes if s.name in names]
        res = warm_up(chosen, group, out, force=True)
        ok = ok and res.cached and not any(st.error for st in res.stages)
    return ok


__all__ = [
    "WARM_STAMP",
    "WarmupResult",
    "builtin_scenes",
    "compiled_solver",
    "is_stamped_warm",
    "stamp_warm",
    "supported",
    "tasks_for",
    "warm_keys",
    "warm_up",
    "warm_up_command",
    "warming",
]
