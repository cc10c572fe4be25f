"""The campaign: seeded scenes through one executor, each judged, every new disagreement shrunk.

Order of work:

1. ``OUT`` is proven new, empty or this campaign's and locked, and ``OUT/manifest.json`` lists
   every file the campaign writes there, before it is written
   (:mod:`validation.studies.fuzz.directory`: a directory holding anything else, or another
   campaign, is refused naming ``out``; a file changed since the campaign wrote it is refused
   naming the file); ``OUT/campaign_config.json`` is written;
2. scene ``i`` of the seed (:func:`validation.studies.fuzz.space.draw_scene_dict`) goes to the
   executor as :func:`judge_index` (a module-level task: process pool, Dask), at most
   ``2 × workers`` at a time, until the budget (scenes) or the time (minutes) is spent;
3. results are taken **in index order** (whatever order they finish in): each is written at once
   to ``OUT/scenes/<i>.json``; a scene's first disagreement not seen before (a plant failing, else a
   referee outlier, else a failed check) is shrunk here (:mod:`validation.studies.fuzz.shrink`;
   each candidate judged on the same executor, so its plant runs have the same hard time limit)
   and written at once as ``OUT/counterexamples/<key>.toml`` (:mod:`validation.studies.fuzz.toml`);
4. ``campaign.md``, ``campaign.json``, ``campaign.png`` (:mod:`validation.studies.fuzz.report`).

Taking results in index order makes everything after the plants deterministic: a seed gives the
same scenes, verdicts and counterexamples on a serial run, a process pool and Dask. An interrupted
campaign keeps every scene and counterexample written; run again with the same ``out``, it skips
the scenes already judged and the disagreements already shrunk, reading back only files whose size
and SHA-256 its manifest lists.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, Future
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from analytic.plant import Plant
from mj_bridge.plants import installed_plants, plant
from validation.report.provenance import dumps
from validation.studies.dask_options import check_dask_options
from validation.studies.fuzz.directory import (
    CONFIG_FILE,
    COUNTEREXAMPLES_DIR,
    SCENES_DIR,
    CampaignDir,
    ChangedRecord,
    open_campaign,
)
from validation.studies.fuzz.judge import (
    RUN_BUDGET_S,
    Kind,
    Outcome,
    judge_scene,
    outcome_of,
    plant_name,
    plant_task,
    prepare,
)
from validation.studies.fuzz.known import recognise
from validation.studies.fuzz.records import (
    CampaignResult,
    Counterexample,
    FuzzConfig,
    SceneRecord,
)
from validation.studies.fuzz.report import FIGURE, campaign_doc, campaign_markdown, campaign_png
from validation.studies.fuzz.settle import Settlement, settle, settle_collect, settle_plant
from validation.studies.fuzz.shrink import MAX_EVALUATIONS, shrink
from validation.studies.fuzz.space import draw_scene_dict
from validation.studies.fuzz.toml import counterexample_toml, slug
from validation.studies.sweep.running import executor_for

DEFAULT_BUDGET = 40
"""Scenes of a campaign given neither a budget nor minutes."""
DEFAULT_HORIZON_S = 0.5
"""Horizon of every scene, s: short (50 output samples), so a campaign covers many scenes."""
SHRINK_BUDGET_FACTOR = 5.0
SHRINK_BUDGET_MIN_S = 2.0
"""A shrink candidate's plant run gets this many times the slowest plant run of the scene it was
found in (at least SHRINK_BUDGET_MIN_S s, at most judge.RUN_BUDGET_S) before it is stopped as over
its time limit (then the candidate does not show the disagreement: not taken)."""
SCENE_WINDOW = 4
"""Scenes submitted ahead per worker: each scene's plants are separate tasks, and the queue must
stay full while this process waits for a scene in index order or shrinks a finding (its
candidates queue behind the scenes already submitted), so no worker idles."""
PRIORITY = {Kind.RAISED: 0, Kind.STOPPED: 1, Kind.OUTLIER: 2, Kind.CHECK: 3}
"""Which of a scene's disagreements is shrunk: a plant failing first, then an outlier, a check."""


def scene_plant_task(
    seed: int, index: int, p: Plant | str, horizon: float, time_limit_s: float = RUN_BUDGET_S,
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
    seed: int, index: int, plants: Sequence[Plant | str], horizon: float,
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


class SerialExecutor(Executor):
    """Every task run at once, here (an ``Executor`` for a serial campaign and for tests)."""

    def submit(self, fn, /, *args, **kwargs):
        f: Future = Future()
        try:
            f.set_result(fn(*args, **kwargs))
        except BaseException as exc:
            if isinstance(exc, KeyboardInterrupt):
                raise
            f.set_exception(exc)
        return f


def _default_plants() -> tuple[str, ...]:
    return tuple(plant_name(p) for p in installed_plants())


def _json_bytes(doc: Any) -> bytes:
    return (json.dumps(doc, indent=2) + "\n").encode("utf-8")


def _scene_rel(index: int) -> str:
    return f"{SCENES_DIR}/{index:06d}.json"


def _example_rel(key: str, suffix: str) -> str:
    return f"{COUNTEREXAMPLES_DIR}/{slug(key)}{suffix}"


def _malformed(cd: CampaignDir, rel: str, exc: BaseException) -> ChangedRecord:
    """A record whose bytes the manifest lists but which does not read as one (a forged pair)."""
    why = f"{type(exc).__name__}: {exc}".splitlines()[0][:120]
    return ChangedRecord(
        f"{cd.path(rel)}: not a record this campaign wrote ({why}); delete it to have the "
        "campaign redo it, or give a new output directory"
    )


def _load_scene_record(cd: CampaignDir, cfg: FuzzConfig, index: int) -> SceneRecord | None:
    rel = _scene_rel(index)
    d = cd.read_json(rel)
    if d is None:
        return None
    try:
        outcome = Outcome.from_dict(d)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise _malformed(cd, rel, exc) from None
    return SceneRecord(index, draw_scene_dict(cfg.seed, index, cfg.horizon), outcome)


def _load_counterexample(cd: CampaignDir, target: Any) -> Counterexample | None:
    """The counterexample of ``target`` shrunk before an interruption (kept as it was written)."""
    rel = _example_rel(target.key, ".json")
    done = cd.read_json(rel)
    if done is None:
        return None
    try:
        name = f"{slug(target.key)}.toml"
        if done["file"] != name:
            raise ValueError(f"file {str(done['file'])[:40]!r}, not {name!r}")
        return Counterexample(
            target,
            int(done["found_in"]),
            dict(done["scene"]),
            float(done["horizon"]),
            Outcome.from_dict(done["outcome"]),
            int(done["evaluations"]),
            str(done["known"]),
            cd.path(f"{COUNTEREXAMPLES_DIR}/{name}"),
            settlement=(
                Settlement.from_dict(done["settlement"]) if done.get("settlement") else None
            ),
        )
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise _malformed(cd, rel, exc) from None


def _write_report(cd: CampaignDir, res: CampaignResult) -> CampaignResult:
    """``campaign.md``, ``campaign.json``, ``campaign.png`` (:mod:`validation.studies.fuzz.report`),
    each listed in the campaign's manifest; the result with ``files`` set."""
    doc = campaign_doc(res)
    files = {
        "png": cd.write(FIGURE, campaign_png(doc)),
        "md": cd.write("campaign.md", campaign_markdown(res, doc).encode("utf-8")),
        "json": cd.write("campaign.json", dumps(doc).encode("utf-8")),
    }
    return replace(res, files=files)


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
        progress: called with one line per finding.
        report: write campaign.md / campaign.json / campaign.png at the end.
        time_limit_s: wall-time limit of one plant's run, s (:data:`judge.RUN_BUDGET_S`): a run
            past it is stopped and counted as a timeout (:mod:`validation.studies.fuzz.judge`).

    Raises:
        ValueError: naming the argument for a bad budget, minutes, horizon, plants or ``out``.
    """

    if budget is not None and (isinstance(budget, bool) or not isinstance(budget, int) or budget < 1):
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
        raise ValueError(f"time_limit_s: must be a positive number of seconds (got {time_limit_s!r})")
    if budget is None and minutes is None:
        budget = DEFAULT_BUDGET
    chosen: tuple[Plant | str, ...] = tuple(plants) if plants is not None else _default_plants()
    if len(chosen) < 2:
        raise ValueError(f"plants: a campaign compares at least two plants (got {chosen!r})")
    names = tuple(plant_name(p) for p in chosen)
    if len(set(names)) != len(names):
        raise ValueError(f"plants: each plant once (got {', '.join(names)})")
    for p in chosen:  # an unknown name is refused here, before any work
        if isinstance(p, str):
            plant(p)
    cfg = FuzzConfig(seed, names, float(horizon), float(time_limit_s))
    if executor is None:  # before anything is created: a bound on the count, the scheduler answers
        check_dask_options(scheduler, dask_workers)
    out = Path(out_dir)
    with open_campaign(out, cfg.to_dict()) as cd:
        if cd.read(CONFIG_FILE) is None:
            cd.write(CONFIG_FILE, _json_bytes(cfg.to_dict()))
        result = _campaign(
            cd, cfg, chosen, budget, minutes, executor, scheduler, dask_workers,
            shrink_evaluations, progress, report, time_limit_s,
        )
    return result


def _campaign(
    cd: CampaignDir,
    cfg: FuzzConfig,
    chosen: tuple[Plant | str, ...],
    budget: int | None,
    minutes: float | None,
    executor: Executor | None,
    scheduler: str | None,
    dask_workers: int | None,
    shrink_evaluations: int,
    progress: Callable[[str], None] | None,
    report: bool,
    time_limit_s: float,
) -> CampaignResult:
    """The campaign's work in its proven, locked directory ``cd`` (:func:`fuzz`)."""
    out, seed, names = cd.root, cfg.seed, cfg.plants
    say = progress or (lambda _m: None)
    t0 = time.perf_counter()
    deadline = t0 + 60.0 * minutes if minutes is not None else None
    records: dict[int, SceneRecord] = {}
    examples: dict[str, Counterexample] = {}
    occurrences: dict[str, int] = {}

    shrink_budget = [float(time_limit_s)]
    pool: list[Executor] = []
    shrink_plants: list[tuple[Plant | str, ...]] = [chosen]

    def submit(data: dict[str, Any], h: float) -> Pending:
        # on the campaign's executor, each plant its own task (they run side by side): a
        # process pool's worker is single-threaded, so each plant run forks and is killed at
        # its limit (judge module docstring)
        return submit_scene(
            pool[0], data, shrink_plants[0], h, shrink_budget[0], candidate_plant_task, data
        )

    def evaluate(data: dict[str, Any], h: float) -> Outcome:
        return submit(data, h).outcome()

    def take(rec: SceneRecord) -> None:
        records[rec.index] = rec
        for d in rec.outcome.disagreements:
            occurrences[d.key] = occurrences.get(d.key, 0) + 1
        fresh = [d for d in rec.outcome.disagreements if d.key not in examples]
        if not fresh:
            return
        target = min(fresh, key=lambda d: (PRIORITY[d.kind], d))
        done = _load_counterexample(cd, target)
        if done is not None:  # shrunk before an interruption: kept as it was written
            ex = done
        else:
            say(f"scene {rec.index}: {target.key}: shrinking")
            # a simpler scene costs less than the one found: a candidate taking far longer (a
            # stiffer variant) is over budget, hence not taken, instead of stalling the campaign
            # a run stopped at its limit says nothing of what a finished run costs: left out
            slowest = max(
                (w for p, w in rec.outcome.walls.items() if p not in rec.outcome.timeouts),
                default=0.0,
            )
            shrink_budget[0] = min(
                time_limit_s, max(SHRINK_BUDGET_MIN_S, SHRINK_BUDGET_FACTOR * slowest)
            )
            # a plant raising or stopping is its own: the candidates run on that plant alone
            alone = target.kind in (Kind.RAISED, Kind.STOPPED)
            shrink_plants[0] = tuple(
                p for p in chosen if not alone or plant_name(p) == target.plant
            )
            s = shrink(
                rec.data, cfg.horizon, target, evaluate, shrink_evaluations, rec.outcome,
                submit, lookahead[0],
            )
            path = cd.path(_example_rel(target.key, ".toml"))
            # settled on the campaign's executor too: each plant at its default and tightened
            # settings, each run within the campaign's own limit (a tightened run costs more)
            # (a plant raising or stopping: only it tightened, every other plant at its default
            # settings within the shrink's limit, to see whether they stop at the same time)
            # each plant's part its own task, side by side
            scene_s, refused_s, chosen_s = prepare(s.data, chosen, s.horizon)
            by_name = {plant_name(p): p for p in chosen}
            limit = shrink_budget[0] if alone else float(time_limit_s)
            parts = [
                pool[0].submit(
                    settle_plant, s.data, by_name[n], s.horizon, limit,
                    not alone or n == target.plant, i == 0,  # the first plant: conditioning
                )
                for i, (n, _) in enumerate(chosen_s)
            ]
            task = settle_collect(scene_s, s.horizon, refused_s, [f.result() for f in parts])
            settled = settle(target, s.outcome, task, names)
            ex = Counterexample(
                target, rec.index, s.data, s.horizon, s.outcome, s.evaluations,
                recognise(rec.data, s.data, target), path, settlement=settled,
            )
            cd.write(_example_rel(target.key, ".toml"), counterexample_toml(ex, cfg).encode())
            cd.write(_example_rel(target.key, ".json"), _json_bytes(ex.to_dict()))
            say(f"  -> {path.name} ({s.evaluations} evaluations"
                f"{', known: ' + ex.known if ex.known else ''}; {settled.cause.value}: {settled.text})")
        examples[target.key] = ex

    def more(i: int) -> bool:
        if budget is not None and i >= budget:
            return False
        return deadline is None or time.perf_counter() < deadline

    complete = False
    lookahead = [1]
    with executor_for(executor, scheduler, dask_workers) as (ex, workers):
        pool.append(ex)
        # candidates evaluated side by side while shrinking (one at a time where tasks run at once)
        lookahead[0] = 1 if isinstance(ex, SerialExecutor) else max(1, workers)
        pending: dict[int, Pending | SceneRecord] = {}
        index = 0
        window = SCENE_WINDOW * max(1, workers)
        try:
            while True:
                while len(pending) < window and more(index):
                    rec = _load_scene_record(cd, cfg, index)
                    if rec is not None:  # resumed: judged before
                        pending[index] = rec
                    else:
                        data = draw_scene_dict(seed, index, cfg.horizon)
                        pending[index] = submit_scene(
                            ex, data, chosen, cfg.horizon, float(time_limit_s),
                            scene_plant_task, seed, index,
                        )
                    index += 1
                if not pending:
                    complete = True
                    break
                first = min(pending)
                got = pending.pop(first)
                if isinstance(got, SceneRecord):
                    take(got)
                    continue
                outcome = got.outcome()
                cd.write(_scene_rel(first), _json_bytes(outcome.to_dict()))
                take(SceneRecord(first, draw_scene_dict(seed, first, cfg.horizon), outcome))
        finally:
            for got in pending.values():
                for f in getattr(got, "futures", ()):
                    f.cancel()
    for key, ex_ in list(examples.items()):
        examples[key] = _with_occurrences(ex_, occurrences.get(key, 1))
    result = CampaignResult(
        cfg,
        out,
        tuple(records[i] for i in sorted(records)),
        tuple(examples[k] for k in sorted(examples)),
        time.perf_counter() - t0,
        complete,
    )
    if report:
        result = _write_report(cd, result)
    return result


def _with_occurrences(ex: Counterexample, k: int) -> Counterexample:
    return replace(ex, occurrences=k)


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
