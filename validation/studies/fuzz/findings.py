"""A campaign's evidence: each judged scene taken in index order, and its first disagreement not
seen before shrunk, settled and written as a counterexample.

:class:`Findings` is given the scenes' records in index order (:meth:`Findings.take`). For a
scene's first disagreement not seen before (a plant failing, else a referee outlier, else a failed
check: :data:`PRIORITY`) it shrinks the scene (:mod:`validation.studies.fuzz.shrink`), each
candidate's plants submitted to the campaign's executor (so each run has the same hard time
limit), settles the minimal scene on that executor too (:mod:`validation.studies.fuzz.settle`), and
writes ``counterexamples/<key>.toml`` and ``.json`` at once. A counterexample written before an
interruption is read back instead (:func:`~validation.studies.fuzz.campaign_records.load_counterexample`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import replace
from typing import Any, Protocol

from analytic.plant import Plant
from validation.studies.fuzz.campaign_records import example_rel, json_bytes, load_counterexample
from validation.studies.fuzz.directory import CampaignDir
from validation.studies.fuzz.judge import Disagreement, Kind, Outcome, plant_name, prepare
from validation.studies.fuzz.known import recognise
from validation.studies.fuzz.records import Counterexample, FuzzConfig, SceneRecord
from validation.studies.fuzz.settle import settle, settle_collect, settle_plant
from validation.studies.fuzz.shrink import shrink
from validation.studies.fuzz.toml import counterexample_toml

SHRINK_BUDGET_FACTOR = 5.0
SHRINK_BUDGET_MIN_S = 2.0
"""A shrink candidate's plant run gets this many times the slowest plant run of the scene it was
found in (at least SHRINK_BUDGET_MIN_S s, at most the campaign's time limit) before it is stopped
as over its time limit (then the candidate does not show the disagreement: not taken)."""
PRIORITY = {Kind.RAISED: 0, Kind.STOPPED: 1, Kind.OUTLIER: 2, Kind.CHECK: 3}
"""Which of a scene's disagreements is shrunk: a plant failing first, then an outlier, a check."""


class Evaluation(Protocol):
    """A candidate's plant runs under way (:class:`validation.studies.fuzz.campaign.Pending`)."""

    def cancel(self) -> None: ...

    def outcome(self) -> Outcome: ...


SubmitCandidate = Callable[[dict[str, Any], Sequence[Plant | str], float, float], Evaluation]
"""``submit(data, plants, horizon, limit_s)``: a candidate's plants submitted to the executor."""


class Findings:
    """The campaign's scene records and counterexamples (module docstring).

    Args:
        cd: the campaign's directory.
        cfg: the campaign's configuration.
        chosen: the plants, in the comparison's order.
        executor: where shrink candidates and settling runs go.
        submit: how a shrink candidate's plants are submitted there.
        lookahead: shrink candidates evaluated side by side.
        shrink_evaluations: most scene evaluations per shrink.
        say: one line per finding.
    """

    def __init__(
        self,
        cd: CampaignDir,
        cfg: FuzzConfig,
        chosen: Sequence[Plant | str],
        executor: Executor,
        submit: SubmitCandidate,
        lookahead: int,
        shrink_evaluations: int,
        say: Callable[[str], None],
    ):
        self._cd, self._cfg, self._chosen = cd, cfg, tuple(chosen)
        self._ex, self._submit, self._lookahead = executor, submit, lookahead
        self._evaluations, self._say = shrink_evaluations, say
        self.records: dict[int, SceneRecord] = {}
        self._examples: dict[str, Counterexample] = {}
        self._occurrences: dict[str, int] = {}

    def take(self, rec: SceneRecord) -> None:
        """Scene ``rec`` judged: kept, its disagreements counted, the first fresh one shrunk."""
        self.records[rec.index] = rec
        for d in rec.outcome.disagreements:
            self._occurrences[d.key] = self._occurrences.get(d.key, 0) + 1
        fresh = [d for d in rec.outcome.disagreements if d.key not in self._examples]
        if not fresh:
            return
        target = min(fresh, key=lambda d: (PRIORITY[d.kind], d))
        done = load_counterexample(self._cd, target)
        # shrunk before an interruption: kept as it was written
        self._examples[target.key] = done if done is not None else self._shrunk(rec, target)

    def scene_records(self) -> tuple[SceneRecord, ...]:
        """Every scene taken, in index order."""
        return tuple(self.records[i] for i in sorted(self.records))

    def counterexamples(self) -> tuple[Counterexample, ...]:
        """Every counterexample, by key, each with how many scenes showed its disagreement."""
        return tuple(
            replace(self._examples[k], occurrences=self._occurrences.get(k, 1))
            for k in sorted(self._examples)
        )

    def _shrunk(self, rec: SceneRecord, target: Disagreement) -> Counterexample:
        """``target`` of scene ``rec`` shrunk, settled and written."""
        cd, cfg, chosen = self._cd, self._cfg, self._chosen
        limit_s = cfg.time_limit_s
        self._say(f"scene {rec.index}: {target.key}: shrinking")
        # a simpler scene costs less than the one found: a candidate taking far longer (a
        # stiffer variant) is over budget, hence not taken, instead of stalling the campaign
        # a run stopped at its limit says nothing of what a finished run costs: left out
        slowest = max(
            (w for p, w in rec.outcome.walls.items() if p not in rec.outcome.timeouts),
            default=0.0,
        )
        budget = min(limit_s, max(SHRINK_BUDGET_MIN_S, SHRINK_BUDGET_FACTOR * slowest))
        # a plant raising or stopping is its own: the candidates run on that plant alone
        alone = target.kind in (Kind.RAISED, Kind.STOPPED)
        plants = tuple(p for p in chosen if not alone or plant_name(p) == target.plant)

        def submit(data: dict[str, Any], h: float) -> Evaluation:
            # each plant its own task (they run side by side): a process pool's worker is
            # single-threaded, so each plant run forks and is killed at its limit
            return self._submit(data, plants, h, budget)

        s = shrink(
            rec.data,
            cfg.horizon,
            target,
            lambda data, h: submit(data, h).outcome(),
            self._evaluations,
            rec.outcome,
            submit,
            self._lookahead,
        )
        path = cd.path(example_rel(target.key, ".toml"))
        # settled on the campaign's executor too: each plant at its default and tightened
        # settings, each run within the campaign's own limit (a tightened run costs more)
        # (a plant raising or stopping: only it tightened, every other plant at its default
        # settings within the shrink's limit, to see whether they stop at the same time)
        # each plant's part its own task, side by side
        scene_s, refused_s, chosen_s = prepare(s.data, chosen, s.horizon)
        by_name = {plant_name(p): p for p in chosen}
        limit = budget if alone else float(limit_s)
        parts = [
            self._ex.submit(
                settle_plant,
                s.data,
                by_name[n],
                s.horizon,
                limit,
                not alone or n == target.plant,
                i == 0,  # the first plant: conditioning
            )
            for i, (n, _) in enumerate(chosen_s)
        ]
        task = settle_collect(scene_s, s.horizon, refused_s, [f.result() for f in parts])
        settled = settle(target, s.outcome, task, cfg.plants)
        ex = Counterexample(
            target,
            rec.index,
            s.data,
            s.horizon,
            s.outcome,
            s.evaluations,
            recognise(rec.data, s.data, target),
            path,
            settlement=settled,
        )
        cd.write(example_rel(target.key, ".toml"), counterexample_toml(ex, cfg).encode())
        cd.write(example_rel(target.key, ".json"), json_bytes(ex.to_dict()))
        self._say(
            f"  -> {path.name} ({s.evaluations} evaluations"
            f"{', known: ' + ex.known if ex.known else ''}; {settled.cause.value}: {settled.text})"
        )
        return ex


__all__ = ["PRIORITY", "SHRINK_BUDGET_FACTOR", "SHRINK_BUDGET_MIN_S", "Findings"]
