"""The campaign: seeded scenes through one executor, each judged, every new disagreement shrunk.

:func:`fuzz` is its steps:

1. **request**: the arguments checked into a :class:`FuzzConfig` (a bad one is a ``ValueError``
   naming it, before any work); ``OUT`` is proven new, empty or this campaign's and locked, and
   ``OUT/manifest.json`` lists every file the campaign writes there, before it is written
   (:mod:`validation.studies.fuzz.directory`: a directory holding anything else, or another
   campaign, is refused naming ``out``; a file changed since the campaign wrote it is refused
   naming the file); ``OUT/campaign_config.json`` is written;
2. **plants**: scene ``i`` of the seed (:func:`validation.studies.fuzz.space.draw_scene_dict`) goes
   to the executor as one task per plant (:func:`submit_scene`, :func:`scene_plant_task`), at
   most :data:`SCENE_WINDOW` per worker ahead, until the budget (scenes) or the time (minutes) is
   spent (a plant that runs batches natively gets a block's scenes of one structure as one task
   instead: :mod:`validation.studies.fuzz.campaign_batches`), and the scenes are taken back
   **in index order** whatever order they finish in
   (:func:`validation.runs.ordered.in_index_order`; where the executor comes from and how it is
   shut down: :func:`validation.studies.sweep.running.executor_for`);
3. **comparison**: each scene's runs judged (:meth:`Pending.outcome`) and written at once to
   ``OUT/scenes/<i>.json``;
4. **evidence**: a scene's first disagreement not seen before shrunk, settled and written as
   ``OUT/counterexamples/<key>.toml`` (:class:`validation.studies.fuzz.findings.Findings`), and at
   the end ``campaign.md``, ``campaign.json``, ``campaign.png``
   (:mod:`validation.studies.fuzz.report`).

Taking results in index order makes everything after the plants deterministic: a seed gives the
same scenes, verdicts and counterexamples on a serial run, a process pool and Dask. An interrupted
campaign keeps every scene and counterexample written; run again with the same ``out``, it skips
the scenes already judged and the disagreements already shrunk, reading back only files whose size
and SHA-256 its manifest lists (:mod:`validation.studies.fuzz.campaign_records`).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, Future
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from analytic.plant import Plant
from analytic.runtime.log import get_logger
from mj_bridge.plants import installed_plants, plant
from validation.report.provenance import dumps
from validation.runs.ordered import SerialExecutor, in_index_order
from validation.runs.progress import counter
from validation.studies.dask_options import check_dashboard, check_dask_options
from validation.studies.fuzz.campaign_batches import CampaignBatches, batched_plants
from validation.studies.fuzz.campaign_records import json_bytes, load_scene_record, scene_rel
from validation.studies.fuzz.directory import CONFIG_FILE, CampaignDir, open_campaign
from validation.studies.fuzz.findings import Findings
from validation.studies.fuzz.html_report import HTML_NAME, campaign_html
from validation.studies.fuzz.judge import (
    RUN_BUDGET_S,
    Outcome,
    judge_scene,
    outcome_of,
    plant_name,
    plant_task,
    prepare,
)
from validation.studies.fuzz.records import (
    CampaignResult,
    Counterexample,
    FuzzConfig,
    SceneRecord,
)
from validation.studies.fuzz.report import FIGURE, campaign_doc, campaign_markdown, campaign_png
from validation.studies.fuzz.shrink import MAX_EVALUATIONS
from validation.studies.fuzz.space import draw_scene_dict
from validation.studies.sweep.running import executor_for

log = get_logger(__name__)

DEFAULT_BUDGET = 40
"""Scenes of a campaign given neither a budget nor minutes."""
DEFAULT_HORIZON_S = 0.5
"""Horizon of every scene, s: short (50 output samples), so a campaign covers many scenes."""
SCENE_WINDOW = 4
"""Scenes submitted ahead per worker: each scene's plants are separate tasks, and the queue must
stay full while this process waits for a scene in index order or shrinks a finding (its
candidates queue behind the scenes already submitted), so no worker idles."""


def scene_plant_task(
    seed: int,
    index: int,
    p: Plant | str,
    horizon: float,
    time_limit_s: float = RUN_BUDGET_S,
) -> dict:
    """Plant ``p``'s run of scene ``index`` of ``seed`` within ``time_limit_s`` s (the executor's
    task for a campaign scene: :func:`validation.studies.fuzz.judge.plant_task`)."""
    return plant_task(draw_scene_dict(seed, index, horizon), p, horizon, time_limit_s)


def candidate_plant_task(
    data: dict[str, Any], p: Plant | str, horizon: float, budget_s: float
) -> dict:
    """Plant ``p``'s run of a shrink candidate within ``budget_s`` s (the executor's task)."""
    return plant_task(data, p, horizon, budget_s)


def judge_index(
    seed: int,
    index: int,
    plants: Sequence[Plant | str],
    horizon: float,
    time_limit_s: float = RUN_BUDGET_S,
) -> dict:
    """Scene ``index`` of ``seed`` judged on ``plants`` here, one plant after the other, each run
    within ``time_limit_s`` s: the outcome as a dict. (A campaign submits the plants of a scene
    as separate tasks instead, :func:`submit_scene`; this is the same judgement in one call.)"""
    data = draw_scene_dict(seed, index, horizon)
    return judge_scene(data, plants, horizon, budget_s=time_limit_s).to_dict()


@dataclass
class Pending:
    """A scene (or shrink candidate) whose plants run as separate tasks: its prepared scene, the
    refusals, and each plant's future, in the plants' order (:func:`submit_scene`)."""

    scene: Any
    horizon: float
    refused: dict[str, str]
    futures: list[Future]

    def cancel(self) -> None:
        """Drop the runs not yet started (a shrink candidate no longer needed)."""
        for f in self.futures:
            f.cancel()

    def outcome(self) -> Outcome:
        """Wait for every plant's run and judge them (:func:`~validation.studies.fuzz.judge.outcome_of`)."""
        if self.scene is None:
            return Outcome(refused=self.refused)
        runs = [f.result()["run"] for f in self.futures]
        return outcome_of(self.scene, self.horizon, self.refused, runs)


def submit_scene(
    ex: Executor,
    data: dict[str, Any],
    plants: Sequence[Plant | str],
    horizon: float,
    limit_s: float,
    task: Callable[..., dict],
    *identity: Any,
) -> Pending:
    """Prepare the scene file's dict ``data`` here (a refusal needs no run) and submit one task
    per plant that can run it, ``task(*identity, plant, horizon, limit_s)``: ``identity`` names
    the scene to the task (``seed, index`` for :func:`scene_plant_task`, ``data`` for
    :func:`candidate_plant_task`), ``limit_s`` is each run's time limit, s."""
    scene, refused, chosen = prepare(data, plants, horizon)
    if scene is None:
        return Pending(None, horizon, refused, [])
    by_name = {plant_name(p): p for p in plants}
    futures = [ex.submit(task, *identity, by_name[name], horizon, limit_s) for name, _ in chosen]
    return Pending(scene, horizon, refused, futures)


def fuzz(
    out_dir: str | Path,
    *,
    budget: int | None = None,
    minutes: float | None = None,
    seed: int = 0,
    plants: Sequence[Plant | str] | None = None,
    horizon: float = DEFAULT_HORIZON_S,
    executor: Executor | None = None,
    scheduler: str | None = None,
    dask_workers: int | None = None,
    shrink_evaluations: int = MAX_EVALUATIONS,
    progress: Callable[[str], None] | None = None,
    report: bool = True,
    time_limit_s: float = RUN_BUDGET_S,
    dashboard: bool = False,
) -> CampaignResult:
    """Run a differential fuzzing campaign into ``out_dir`` (module docstring).

    Args:
        budget: scenes to judge (default :data:`DEFAULT_BUDGET` unless ``minutes`` is given).
        minutes: stop submitting scenes after this much wall time (with ``budget``: whichever
            comes first).
        seed: the campaign's seed.
        plants: names (any registered plant) or :class:`analytic.plant.Plant` instances, in the
            comparison's order (default every installed plant).
        horizon: of every scene, s.
        executor: where the scenes are judged (any ``concurrent.futures.Executor``); else a Dask
            cluster at ``scheduler`` or a local one of ``dask_workers`` workers, else a local
            process pool (:func:`validation.studies.sweep.running.executor_for`).
        shrink_evaluations: most scene evaluations per shrink.
        progress: called with one line per finding (default: each line logged at ``INFO`` on
            this module's logger, :mod:`analytic.runtime.log`); the scenes judged are counted
            (``12/40 scenes``, with an ETA) under the progress display in force
            (:func:`validation.runs.progress.counter`).
        report: write campaign.md / campaign.json / campaign.png at the end.
        time_limit_s: wall-time limit of one plant's run, s (:data:`judge.RUN_BUDGET_S`): a run
            past it is stopped and counted as a timeout (:mod:`validation.studies.fuzz.judge`).
        dashboard: the local Dask cluster of ``dask_workers`` serves its dashboard on 127.0.0.1,
            its link logged (:mod:`validation.studies.dask_options`).

    Raises:
        ValueError: naming the argument for a bad budget, minutes, horizon, plants or ``out``.
    """
    cfg, chosen, budget = _checked(budget, minutes, seed, plants, horizon, time_limit_s)
    if executor is None:  # before anything is created: a bound on the count, the scheduler answers
        check_dask_options(scheduler, dask_workers)
        check_dashboard(dashboard, scheduler, dask_workers)
    say = progress or log.info
    with open_campaign(Path(out_dir), cfg.to_dict()) as cd:
        if cd.read(CONFIG_FILE) is None:
            cd.write(CONFIG_FILE, json_bytes(cfg.to_dict()))
        t0 = time.perf_counter()
        deadline = t0 + 60.0 * minutes if minutes is not None else None

        def more(i: int) -> bool:
            if budget is not None and i >= budget:
                return False
            return deadline is None or time.perf_counter() < deadline

        cluster = executor_for(executor, scheduler, dask_workers, dashboard=dashboard)
        with cluster as (ex, workers):
            findings = Findings(
                cd,
                cfg,
                chosen,
                ex,
                lambda data, ps, h, limit: submit_scene(
                    ex, data, ps, h, limit, candidate_plant_task, data
                ),
                # candidates side by side while shrinking (one at a time where tasks run at once)
                1 if isinstance(ex, SerialExecutor) else max(1, workers),
                shrink_evaluations,
                say,
            )
            batched = batched_plants(chosen)  # their scenes of one structure: one call each
            batches = CampaignBatches(cd, cfg, chosen, ex, budget, batched) if batched else None

            def start(i: int) -> Pending | SceneRecord:
                if batches is None:
                    return _start_scene(cd, cfg, chosen, ex, i)
                return batches.start(i, Pending, scene_plant_task)

            scenes = in_index_order(start, more, SCENE_WINDOW * max(1, workers), _cancel)
            label = f"fuzz seed {cfg.seed}"
            for_s = None if minutes is None else 60.0 * minutes
            try:
                with scenes as taken, counter(label, budget, "scenes", deadline_s=for_s) as c:
                    for index, got in taken:  # the plants' runs, in index order
                        findings.take(
                            got if isinstance(got, SceneRecord) else _judged(cd, cfg, index, got)
                        )
                        c.advance()
            finally:
                if batches is not None:
                    batches.close()
        result = CampaignResult(
            cfg,
            cd.root,
            findings.scene_records(),
            findings.counterexamples(),
            time.perf_counter() - t0,
            True,
        )
        if report:
            result = _write_report(cd, result)
    return result


def _checked(
    budget: int | None,
    minutes: float | None,
    seed: int,
    plants: Sequence[Plant | str] | None,
    horizon: float,
    time_limit_s: float,
) -> tuple[FuzzConfig, tuple[Plant | str, ...], int | None]:
    """:func:`fuzz`'s arguments checked: the configuration, the plants and the scene budget."""
    if budget is not None and (
        isinstance(budget, bool) or not isinstance(budget, int) or budget < 1
    ):
        raise ValueError(f"budget: must be a whole number ≥ 1 (got {budget!r})")
    if minutes is not None and not (isinstance(minutes, int | float) and 0 < minutes < 1e6):
        raise ValueError(f"minutes: must be a positive number (got {minutes!r})")
    if not (isinstance(horizon, int | float) and 0 < horizon < 1e6):
        raise ValueError(f"horizon: must be a positive number of seconds (got {horizon!r})")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"seed: must be a whole number ≥ 0 (got {seed!r})")
    if isinstance(time_limit_s, bool) or not (
        isinstance(time_limit_s, int | float) and 0 < time_limit_s < 1e6
    ):
        raise ValueError(
            f"time_limit_s: must be a positive number of seconds (got {time_limit_s!r})"
        )
    if budget is None and minutes is None:
        budget = DEFAULT_BUDGET
    chosen = tuple(plants) if plants is not None else _default_plants()
    if len(chosen) < 2:
        raise ValueError(f"plants: a campaign compares at least two plants (got {chosen!r})")
    names = tuple(plant_name(p) for p in chosen)
    if len(set(names)) != len(names):
        raise ValueError(f"plants: each plant once (got {', '.join(names)})")
    for p in chosen:  # an unknown name is refused here, before any work
        if isinstance(p, str):
            plant(p)
    return FuzzConfig(seed, names, float(horizon), float(time_limit_s)), chosen, budget


def _default_plants() -> tuple[str, ...]:
    return tuple(plant_name(p) for p in installed_plants())


def _start_scene(
    cd: CampaignDir, cfg: FuzzConfig, chosen: Sequence[Plant | str], ex: Executor, index: int
) -> Pending | SceneRecord:
    """Scene ``index``: its record when it was judged before (a resumed campaign), else its
    plants submitted to ``ex``."""
    rec = load_scene_record(cd, cfg, index)
    if rec is not None:
        return rec
    data = draw_scene_dict(cfg.seed, index, cfg.horizon)
    return submit_scene(
        ex, data, chosen, cfg.horizon, cfg.time_limit_s, scene_plant_task, cfg.seed, index
    )


def _cancel(got: Pending | SceneRecord) -> None:
    if isinstance(got, Pending):
        got.cancel()


def _judged(cd: CampaignDir, cfg: FuzzConfig, index: int, got: Pending) -> SceneRecord:
    """Scene ``index``'s runs judged, its record written at once."""
    outcome = got.outcome()
    cd.write(scene_rel(index), json_bytes(outcome.to_dict()))
    return SceneRecord(index, draw_scene_dict(cfg.seed, index, cfg.horizon), outcome)


def _write_report(cd: CampaignDir, res: CampaignResult) -> CampaignResult:
    """``campaign.md``, ``campaign.json``, ``campaign.png`` (:mod:`validation.studies.fuzz.report`)
    and ``campaign.html`` (:mod:`validation.studies.fuzz.html_report`), each listed in the
    campaign's manifest; the result with ``files`` set."""
    doc = campaign_doc(res)
    png = campaign_png(doc)
    files = {
        "png": cd.write(FIGURE, png),
        "md": cd.write("campaign.md", campaign_markdown(res, doc).encode("utf-8")),
        "json": cd.write("campaign.json", dumps(doc).encode("utf-8")),
        "html": cd.write(HTML_NAME, campaign_html(res, doc, png).encode("utf-8")),
    }
    return replace(res, files=files)


__all__ = [
    "DEFAULT_BUDGET",
    "DEFAULT_HORIZON_S",
    "CampaignResult",
    "Counterexample",
    "FuzzConfig",
    "SceneRecord",
    "SerialExecutor",
    "candidate_plant_task",
    "fuzz",
    "judge_index",
    "scene_plant_task",
    "submit_scene",
]
