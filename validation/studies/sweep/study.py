"""The study: every run through one executor, then the files.

Order of work (each item a task of the executor, a local process pool by default):

1. the kernels compiled once, here (numba's disk cache; workers load them);
2. the reference, from its cache or computed (uncapped, then capped), while the cost of each
   effect is measured (in a user's executor: at the end, in this process);
3. the series, the most expensive first (so that the pool ends together), then the rows of the
   stabilisation study;
4. the cheapest setting per level, and ``sweep.csv``, ``sweep.json``, ``sweep.md``,
   ``work_precision.png``, ``sweep.rrd`` and ``sweep.html`` as one output run (:mod:`validation.runs.outputs`).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Executor, wait
from pathlib import Path
from typing import Any

from analytic.runtime.log import get_logger
from analytic.scene import Scene
from validation.runs.atomic import write_bytes, write_text
from validation.runs.outputs import output_run
from validation.runs.progress import counter
from validation.scenes import resolve_scene
from validation.studies.effects_cost import effects_cost
from validation.studies.sweep import running
from validation.studies.sweep.config import (
    ACCELERATED,
    ANALYTIC,
    FLOOR_FACTOR,
    MUJOCO,
    PINOCCHIO,
    SweepConfig,
)
from validation.studies.sweep.csv_rows import to_csv
from validation.studies.sweep.figure import figure_data, render_png
from validation.studies.sweep.html_report import HTML_NAME, sweep_html
from validation.studies.sweep.json_doc import sweep_json
from validation.studies.sweep.markdown import FIGURE_FILE, skipped_note, sweep_markdown
from validation.studies.sweep.reference import obtain_reference
from validation.studies.sweep.result import SweepResult
from validation.studies.sweep.rrd import write_rrd
from validation.studies.sweep.selection import cheapest_settings
from validation.studies.sweep.series import run_series
from validation.studies.sweep.stabilization import stabilization_row

log = get_logger(__name__)

TICK_S = 1.0
"""How long the grid waits for a series before it ticks its count (a plain progress line is then
written if one is due: a long series still shows time passing in a log)."""

EXPENSIVE_FIRST = {"Radau": 0, "implicit": 1, "RK45": 2, "Euler": 3, "implicitfast": 3, "RK4": 4}
"""Submission order of the series (lower first; others last): the implicit solver and the
integrators with the most steps are the longest tasks, started first so that the workers finish
together."""


def _expense_rank(engine: str, method: str) -> int:
    """Submission rank of a series (lower first): the accelerated plants' (a process and a
    compilation per run) before :data:`EXPENSIVE_FIRST`'s."""
    return -1 if engine in ACCELERATED else EXPENSIVE_FIRST.get(method, 9)


def resolve(scene: Scene | str | None) -> Scene:
    """A Scene as given, else the built-in scene or file of that name (None: the default scene,
    :data:`validation.scenes.DEFAULT_SCENE`): :func:`validation.scenes.resolve_scene`."""
    return resolve_scene(scene)


def run_sweep(
    scene: Scene | str | None,
    out_dir: str | Path,
    *,
    quick: bool = False,
    executor: Executor | None = None,
    progress: Callable[[str], None] | None = None,
    config: SweepConfig | None = None,
    t_end: float | None = None,
    cache_dir: str | Path | None = None,
) -> SweepResult:
    """Run the study on ``scene`` (a Scene, a built-in name or a path; None: the default) and write
    ``sweep.csv``, ``sweep.json``, ``sweep.md``, ``work_precision.png``, ``sweep.rrd`` to ``out_dir``
    as one set (:func:`validation.runs.outputs.output_run`, with ``manifest.json``).

    Args:
        quick: the small grid of :meth:`SweepConfig.quick` (ignored when ``config`` is given).
        executor: where every run goes (any ``concurrent.futures.Executor``); default a local
            process pool, shut down at the end.
        progress: called with one line of text per stage (default: each line logged at
            ``INFO`` on this module's logger, :mod:`analytic.runtime.log`); the series done are
            counted (``3/12 series``) under the progress display in force
            (:func:`validation.runs.progress.counter`).
        config: the grid and limits (default :class:`SweepConfig`).
        t_end: the horizon, s, instead of the configuration's.
        cache_dir: the reference cache's directory (default
            :func:`validation.studies.sweep.reference.default_cache_dir`).
    """
    sc = resolve(scene)
    cfg = config or (SweepConfig.quick() if quick else SweepConfig())
    if t_end is not None:
        cfg = dataclasses.replace(cfg, t_end=t_end)
    sc.output.with_t_end(cfg.t_end, "t_end")  # a horizon the scene cannot take, before any work
    with output_run(out_dir, "sweep") as run:
        res = _sweep_into(
            sc,
            cfg,
            run.path,
            executor=executor,
            progress=progress,
            cache_dir=cache_dir,
            run_id=run.run_id,
        )
    (progress or log.info)(f"wrote {', '.join(sorted(res.files))} to {run.target}")
    return dataclasses.replace(
        res, out_dir=run.target, files={k: run.final(p.name) for k, p in res.files.items()}
    )


def _series_of(cfg: SweepConfig, skipped: dict[str, str]) -> list[tuple[str, str]]:
    series = [(ANALYTIC, m) for m in cfg.solvers] + [(MUJOCO, i) for i in cfg.integrators]
    if PINOCCHIO not in skipped:
        series += [(PINOCCHIO, m) for m in cfg.solvers]
    series += [(e, str(p)) for e, p in cfg.accelerated if e not in skipped]
    return series


def _skip_unavailable(cfg: SweepConfig, skipped: dict[str, str], say) -> None:
    """Pinocchio and every accelerated plant of ``cfg`` that cannot run here, into ``skipped``
    with the reason, each said in one line."""
    why = running.pinocchio_unavailable()
    if why:
        skipped[PINOCCHIO] = why
        say(f"  {skipped_note(PINOCCHIO, why)}")
    for engine in dict.fromkeys(e for e, _ in cfg.accelerated):
        why = running.accelerated_unavailable(engine)
        if why:
            skipped[str(engine)] = why
            say(f"  {skipped_note(engine, why)}")


def _sweep_into(
    sc: Scene,
    cfg: SweepConfig,
    out: Path,
    *,
    executor: Executor | None,
    progress: Callable[[str], None] | None,
    cache_dir: str | Path | None,
    run_id: str | None,
) -> SweepResult:
    """:func:`run_sweep`'s steps, writing into the staging directory ``out``: the kernels
    compiled here, the reference and every series over the executor (the sweep's own pool, shut
    down as :func:`validation.studies.sweep.running.executor_for` does, or the caller's), then the
    files."""
    t_start = time.perf_counter()
    stages: dict[str, float] = {}

    def stage(name: str, since: float) -> float:
        now = time.perf_counter()
        stages[name] = now - since
        return now

    say = progress or log.info
    skipped: dict[str, str] = {}
    _skip_unavailable(cfg, skipped, say)
    # Compile once, here, before any run that is timed or has a wall-time budget (numba's cache).
    say("compiling the kernels (once per machine; later runs load them from numba's cache)")
    running.warm_compiled(sc, skipped)
    t = stage("compile", t_start)
    own = executor is None
    series = _series_of(cfg, skipped)
    with running.executor_for(executor) as (ex, width):
        # effects_cost binds MuJoCo's process-wide control callback: in the sweep's own pool it
        # is a task like any other (one task per process at a time); a user's executor may run
        # it in a thread beside a MuJoCo series, so there it runs here, after the pool
        effects_f = ex.submit(effects_cost, sc, cfg.effects_repeats) if own else None
        reference = obtain_reference(sc, cfg.t_end, ex, cache_dir, say)
        t = stage("reference", t)
        floor = FLOOR_FACTOR * reference.error_estimate
        runs, stab_futs = _grid(ex, sc, cfg, series, reference.samples, floor, say)
        t = stage("series", t)
        stabilization = [f.result() for f in stab_futs]
        effects = effects_f.result() if effects_f is not None else None
    if effects is None:
        effects = effects_cost(sc, cfg.effects_repeats)
    t = stage("stabilization_and_effects", t)
    for i, r in enumerate(runs):
        r["run_id"] = i
    engines = list(dict.fromkeys(e for e, _ in series))
    res = SweepResult(
        scene=sc.name,
        out_dir=out,
        config=cfg.to_dict(),
        reference=dict(reference.info),
        runs=tuple(runs),
        cheapest=cheapest_settings(runs, cfg.levels, floor, engines=engines),
        stabilization=tuple(stabilization),
        effects=tuple(effects),
        skipped_series=skipped,
        series=tuple((str(e), m) for e, m in series),
        workers=width if own else None,
    )
    files = _write_files(res, sc, cfg, out, floor, run_id)
    t = stage("files", t)
    res = dataclasses.replace(
        res, files=files, wall_time_s=time.perf_counter() - t_start, stage_wall_s=stages
    )
    write_text(files["json"], sweep_json(res, cfg, sc))
    return res


def _grid(
    ex: Executor,
    sc: Scene,
    cfg: SweepConfig,
    series: list[tuple[str, str]],
    samples: Any,
    floor: float,
    say: Callable[[str], None],
) -> tuple[list[dict[str, Any]], list[Any]]:
    """Every series submitted to ``ex``, the most expensive first, then the stabilisation rows;
    the series' rows once each has finished (in ``series``' order) and the rows' futures."""
    say(f"grid: {len(series)} series in the executor")
    order = sorted(range(len(series)), key=lambda i: _expense_rank(*series[i]))
    futs: dict[int, Any] = {}
    for i in order:
        e, m = series[i]
        futs[i] = ex.submit(run_series, sc, e, m, cfg, samples, floor)
    stab_futs = [
        ex.submit(stabilization_row, sc, d1, d2, rt, off, cfg.t_end)
        for rt in cfg.delta_rtols
        for off in (0.0, cfg.delta_norm_offset)
        for d1, d2 in cfg.deltas
    ]
    pending = {f: i for i, f in futs.items()}
    with counter(f"sweep {sc.name}", len(series) or None, "series") as done:
        while pending:  # counted as they end (a tick while none does); rows in series' order
            ended, _ = wait(pending, timeout=TICK_S, return_when=FIRST_COMPLETED)
            done.tick()
            for f in ended:
                e, m = series[pending.pop(f)]
                rows = f.result()
                say(f"  {e} {m}: {sum(r['status'] == 'ok' for r in rows)}/{len(rows)} ok")
                done.advance()
    runs: list[dict[str, Any]] = []
    for i in range(len(series)):
        runs.extend(futs[i].result())
    return runs, stab_futs


def _write_files(
    res: SweepResult, sc: Scene, cfg: SweepConfig, out: Path, floor: float, run_id: str | None
) -> dict[str, Path]:
    """``sweep.csv``, ``sweep.md``, the figure, ``sweep.rrd`` and ``sweep.html`` written into
    ``out`` (``sweep.json``, which holds the wall times, is written last, by the caller); every
    file's path by key."""
    files = {
        "csv": out / "sweep.csv",
        "json": out / "sweep.json",
        "md": out / "sweep.md",
        "html": out / HTML_NAME,
        "png": out / FIGURE_FILE,
        "rrd": out / "sweep.rrd",
    }
    data = figure_data(list(res.runs), floor, sc.name, cfg.t_end)
    png = render_png(data)
    write_text(files["csv"], to_csv(list(res.runs)))
    write_text(files["md"], sweep_markdown(res, cfg))
    write_bytes(files["png"], png)
    write_rrd(files["rrd"], data, png, sweep_markdown(res, cfg, image=None), recording_id=run_id)
    write_text(files["html"], sweep_html(res, cfg, png, files["rrd"].name))
    return files


__all__ = ["run_sweep"]
