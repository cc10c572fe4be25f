"""One run of one plant at one setting, within a wall-time budget; the executor the runs go to.

Everything here is a module-level function: it travels to process-pool workers and Dask.

A run over its budget is stopped by :class:`BudgetExceeded`, raised from the plant's progress
callback. It is an ordinary ``Exception``, not a ``KeyboardInterrupt``: the plants turn a
``KeyboardInterrupt`` into an interrupted run (the user's Ctrl-C or SIGTERM), which the sweep
re-raises so that the whole sweep stops, while a budget stop ends only the series it is in. The two
can never be taken for each other.
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import os
import time
import warnings
from collections.abc import Callable, Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import ExitStack, contextmanager
from typing import Any

import analytic
import mj_bridge
from analytic.effects import Precision
from analytic.runtime.log import get_logger
from analytic.scene import Scene
from mj_bridge.plants import PinocchioPlant, PinocchioSettings, plant, registered
from validation.studies.dask_options import check_dashboard, check_dask_options, dashboard_address
from validation.studies.roundoff import precision_of
from validation.studies.sweep.config import ACCELERATED, PINOCCHIO, RTOL_ENGINES, SweepConfig

log = get_logger(__name__)

MAX_WORKERS = 4
"""Most processes of the default pool (each run is single-threaded; BLAS is pinned to one thread)."""


class BudgetExceeded(Exception):
    """A run passed its wall-time budget; raised from the plant's progress callback.

    Attributes:
        budget_s: the budget, s; elapsed_s: wall time when it was noticed, s; t_reached: the
        simulated time reached, s.
    """

    def __init__(self, budget_s: float, elapsed_s: float, t_reached: float):
        super().__init__(
            f"stopped at its budget of {budget_s:g} s (after {elapsed_s:.3g} s, at t = "
            f"{t_reached:.4g} s)"
        )
        self.budget_s = budget_s
        self.elapsed_s = elapsed_s
        self.t_reached = t_reached


def within_budget(
    run: Callable[[Callable[[float], None] | None], Any],
    budget: float | None,
    from_first_sample: bool = False,
):
    """``run(progress)`` (a plant's run), stopped by :class:`BudgetExceeded` when it takes more
    than ``budget`` s of wall time (checked at each output sample). ``from_first_sample``: the
    clock starts at the first sample after t = 0 (an accelerated plant: its process start and
    its compilation, done before that sample, are not the cost of the setting, and a loaded
    machine stretches them most).

    A run interrupted by the user (Ctrl-C, SIGTERM) comes back interrupted from the plant and is
    re-raised as ``KeyboardInterrupt``, so the sweep stops.
    """
    progress = None
    if budget is not None:
        start = None if from_first_sample else time.perf_counter()

        def progress(t: float) -> None:
            nonlocal start
            if start is None:
                if t <= 0:  # the initial sample, reported before any compilation
                    return
                start = time.perf_counter()
            elapsed = time.perf_counter() - start
            if elapsed > budget:
                raise BudgetExceeded(budget, elapsed, t)

    with warnings.catch_warnings():
        # the plants' quadrature states carry atol 1e300 (outside error control); scipy's
        # first-step heuristic then overflows harmlessly
        warnings.filterwarnings("ignore", "overflow encountered", RuntimeWarning)
        tr = run(progress)
    return tr.raise_if_interrupted()


def analytic_run(scene: Scene, method: str, rtol: float, atol: float, t_end: float, budget=None):
    """One run of the analytic engine (scipy ``method``), within ``budget`` s (:func:`within_budget`)."""
    return within_budget(
        lambda progress: analytic.simulate(
            scene, method=method, rtol=rtol, atol=atol, t_end=t_end, progress=progress
        ),
        budget,
    )


def pinocchio_run(scene: Scene, method: str, rtol: float, atol: float, t_end: float, budget=None):
    """One run of the Pinocchio plant through the plant protocol; ``budget`` as for
    :func:`analytic_run`."""
    settings = PinocchioSettings(method, rtol, atol)
    return within_budget(
        lambda progress: plant(PINOCCHIO).simulate(scene, settings, t_end=t_end, progress=progress),
        budget,
    )


def mujoco_run(scene: Scene, integrator: str, dt: float, t_end: float, budget=None):
    """One MuJoCo run; ``budget`` as for :func:`analytic_run`."""
    return within_budget(
        lambda progress: mj_bridge.simulate(
            scene, integrator=integrator, dt=dt, t_end=t_end, progress=progress
        ),
        budget,
    )


def accelerated_settings(scene: Scene, engine: str, precision: str, dt: float) -> Any:
    """The settings of an accelerated plant's run: the scene's (``default_settings``) with the
    time step ``dt`` and, for a plant that has the field, ``precision``; ``ValueError`` naming
    ``precision`` for a plant that cannot run in it (MuJoCo Warp: float32 only)."""
    pl = plant(engine)
    settings = pl.default_settings(scene)
    changes: dict[str, Any] = {"timestep": float(dt)}
    if "precision" in {f.name for f in dataclasses.fields(settings)}:
        changes["precision"] = Precision(precision)
    elif precision_of(settings) != Precision(precision):
        raise ValueError(
            f"precision: {engine} runs in {precision_of(settings).value} only (got {precision!r})"
        )
    return dataclasses.replace(settings, **changes)


def accelerated_run(
    scene: Scene, engine: str, precision: str, dt: float, t_end: float, budget=None
):
    """One run of an accelerated plant (``mjx``, ``mjwarp``) through the plant protocol at
    ``dt`` in ``precision``; ``budget`` as for :func:`analytic_run`, counted from the first
    output sample (its process start and compilation are not counted; its own ``wall_time_s``
    is what it reports as the integration)."""
    settings = accelerated_settings(scene, engine, precision, dt)
    return within_budget(
        lambda progress: plant(engine).simulate(scene, settings, t_end=t_end, progress=progress),
        budget,
        from_first_sample=True,
    )


def accelerated_unavailable(engine: str) -> str:
    """Why an accelerated plant's series cannot run here ("" when it can): not registered (its
    plugin did not load), or its ``unavailable()`` reason."""
    cls = registered().get(str(engine))
    if cls is None:
        return f"{engine} is not a registered plant here (its plugin did not load)"
    return cls.unavailable()


def run_setting(
    scene: Scene,
    engine: str,
    method: str,
    setting: float,
    cfg: SweepConfig,
    t_end: float | None = None,
    budget: float | None = None,
):
    """One run of ``engine`` / ``method`` at ``setting`` (rtol, atol = rtol x ``cfg.atol_ratio``;
    or MuJoCo's dt; an accelerated plant's dt, ``method`` its precision) over ``t_end``
    (default the engine's horizon, :meth:`SweepConfig.horizon`)."""
    t_end = cfg.horizon(engine) if t_end is None else t_end
    if engine in ACCELERATED:
        return accelerated_run(scene, engine, method, setting, t_end, budget=budget)
    if engine in RTOL_ENGINES:
        run = pinocchio_run if engine == PINOCCHIO else analytic_run
        return run(scene, method, setting, setting * cfg.atol_ratio, t_end, budget=budget)
    return mujoco_run(scene, method, setting, t_end, budget=budget)


def pinocchio_unavailable() -> str:
    """Why the Pinocchio series cannot run here ("" when ``pin`` is installed)."""
    return PinocchioPlant.unavailable()


def warm_compiled(scene: Scene, skipped: Any = ()) -> None:
    """One output interval on every plant that runs (not in ``skipped``): numba compiles the
    kernels once, here, and writes them to its disk cache, from which every worker then loads them
    (~1 s) instead of compiling them (~20 s on a fresh machine) against a run's budget."""
    interval = 1.0 / scene.output.rate
    for engine in sorted(RTOL_ENGINES):
        if engine not in skipped:
            run = pinocchio_run if engine == PINOCCHIO else analytic_run
            run(scene, "DOP853", 1e-6, 1e-8, interval)
    mujoco_run(scene, "RK4", scene.mujoco.timestep, interval)


def default_workers() -> int:
    """Workers of the default pool: one per core this process may use, at most :data:`MAX_WORKERS`."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    return max(1, min(MAX_WORKERS, cores))


def default_executor() -> Executor:
    """A local process pool of :func:`default_workers` workers.

    spawn, not fork: the parent may hold threads (BLAS, numba, a Dask client) that fork would copy
    mid-state; workers import the engines afresh. Each worker ends when this process does, even
    one killed with SIGKILL (:func:`validation.runs.lifetime.pool_initializer`).
    """
    from validation.runs.lifetime import pool_initializer

    return ProcessPoolExecutor(
        max_workers=default_workers(),
        mp_context=multiprocessing.get_context("spawn"),
        initializer=pool_initializer,
        initargs=(os.getpid(),),
    )


def shut_down(ex: Executor, exc: BaseException) -> None:
    """Shut a pool of this process's own down as ``exc`` leaves the work it ran: pending tasks
    cancelled; after an interrupt (Ctrl-C, SIGTERM, or any error once a signal arrived) without
    waiting for the tasks that are running, so the command stops at once (the pool's workers end
    with this process, :func:`validation.runs.lifetime.pool_initializer`); else after them."""
    from validation.runs.interrupts import interrupt_of

    ex.shutdown(wait=interrupt_of(exc) is None, cancel_futures=True)


@contextmanager
def executor_for(
    executor: Executor | None = None,
    scheduler: str | None = None,
    dask_workers: int | None = None,
    dashboard: bool = False,
) -> Iterator[tuple[Executor, int]]:
    """The executor a study's runs go to, and how many run at once; shut down on exit when made
    here.

    ``executor`` as given (left running; its width counted as :func:`default_workers`); else a
    Dask cluster's executor: the scheduler at ``scheduler`` (``tcp://host:8786``), or a
    ``LocalCluster`` of ``dask_workers`` single-threaded worker processes; else the local process
    pool of :func:`default_executor`. Dask is imported only when asked for (``pip install
    "dask[distributed]"``); ``ValueError`` naming ``scheduler`` / ``dask_workers`` for both given,
    a bad count (:mod:`validation.studies.dask_options`), a scheduler that does not answer, or
    Dask not installed. With ``dashboard``, the ``LocalCluster`` serves Dask's dashboard on
    127.0.0.1 (a free port) and its link is logged once at ``INFO``
    (:func:`validation.studies.dask_options.dashboard_address`); without, it has none.
    """
    check_dask_options(scheduler, dask_workers)  # a bound on the count, the scheduler answers
    check_dashboard(dashboard and executor is None, scheduler, dask_workers)
    if executor is not None:
        yield executor, default_workers()
        return
    if scheduler is None and dask_workers is None:
        ex = default_executor()
        try:
            yield ex, default_workers()
        except BaseException as exc:
            shut_down(ex, exc)
            raise
        ex.shutdown(wait=True, cancel_futures=True)
        return
    try:  # deferred: Dask is optional (the [test] extra has it)
        from distributed import Client, LocalCluster
    except ImportError:
        what = "scheduler" if scheduler is not None else "dask_workers"
        raise ValueError(
            f'{what}: Dask is not installed (pip install "dask[distributed]")'
        ) from None
    cluster = None
    scoped = ExitStack()
    if scheduler is None:
        # Dask's worker processes are daemonic by default, and a daemonic process may start no
        # child: a run there could not go to the fork server (validation.runs.workers.can_serve).
        # Not daemonic for this cluster's life (its nanny reads the setting at every worker
        # (re)start); each worker still ends with this process (the nanny's parent pipe).
        import dask

        scoped.enter_context(dask.config.set({"distributed.worker.daemon": False}))
        try:
            cluster = LocalCluster(
                n_workers=dask_workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=dashboard_address(dashboard),
            )
            client = Client(cluster)
        except BaseException:
            scoped.close()
            raise
    else:
        client = Client(scheduler)
    if dashboard:
        log.info(f"Dask dashboard: {client.dashboard_link}")
    try:
        width = sum(w.get("nthreads", 1) for w in client.scheduler_info()["workers"].values())
        # pure=False: Dask would otherwise give two submissions of one call (a shrink candidate
        # met again) one key, and the second could inherit the first's release as a
        # CancelledError; every submission here is its own task
        yield client.get_executor(pure=False), max(1, width)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
        scoped.close()


__all__ = [
    "MAX_WORKERS",
    "BudgetExceeded",
    "accelerated_run",
    "accelerated_settings",
    "accelerated_unavailable",
    "analytic_run",
    "default_executor",
    "default_workers",
    "executor_for",
    "mujoco_run",
    "pinocchio_run",
    "pinocchio_unavailable",
    "run_setting",
    "warm_compiled",
    "within_budget",
]
