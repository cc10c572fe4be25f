"""The campaign's records: its configuration, a judged scene, a minimal counterexample, the
result (plain frozen data; :mod:`validation.studies.fuzz.campaign` makes them)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from validation.studies.fuzz.judge import RUN_BUDGET_S, Disagreement, Outcome
from validation.studies.fuzz.settle import Cause, Settlement


@dataclass(frozen=True)
class FuzzConfig:
    """What a campaign is: its seed, plants and horizon (a resumed campaign must match them), and
    the wall-time limit of its plant runs (not part of what it is: ``to_dict`` leaves it out, a
    resumed campaign may be given another).

    Attributes:
        seed: the campaign's seed (scene ``i`` is drawn from ``[seed, i]``).
        plants: the plants' names, in the order given (the first is the comparison's reference).
        horizon: s.
        time_limit_s: wall-time limit of one plant run, s (the counterexamples' reproduce
            commands carry it).
    """

    seed: int
    plants: tuple[str, ...]
    horizon: float
    time_limit_s: float = RUN_BUDGET_S

    def to_dict(self) -> dict[str, Any]:
        return {"seed": self.seed, "plants": list(self.plants), "horizon": self.horizon}


@dataclass(frozen=True)
class SceneRecord:
    """One judged scene: its index, the scene file's dict, its outcome."""

    index: int
    data: dict[str, Any]
    outcome: Outcome


@dataclass(frozen=True)
class Counterexample:
    """A minimal scene showing one disagreement.

    Attributes:
        disagreement: what it shows.
        found_in: the index of the campaign scene it was shrunk from.
        data, horizon: the minimal scene file's dict, its horizon (s).
        outcome: its judgement.
        evaluations: scene evaluations the shrink made.
        known: the known finding it is (:mod:`validation.studies.fuzz.known`), "" when new.
        path: its TOML file.
        occurrences: campaign scenes showing the same disagreement.
        settlement: whether it is a model difference or a numerical limit of the settings
            (:mod:`validation.studies.fuzz.settle`).
    """

    disagreement: Disagreement
    found_in: int
    data: dict[str, Any]
    horizon: float
    outcome: Outcome
    evaluations: int
    known: str
    path: Path
    occurrences: int = 1
    settlement: Settlement | None = None

    @property
    def counts_against(self) -> bool:
        """A new finding that neither the settings, the scene's own singular motion or
        conditioning, nor an engine's range explain: what fails a campaign."""
        return not self.known and (
            self.settlement is None or self.settlement.cause not in (Cause.SETTINGS, Cause.SCENE, Cause.RANGE, Cause.CONDITIONING)
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "disagreement": self.disagreement.to_dict(),
            "found_in": self.found_in,
            "horizon": self.horizon,
            "evaluations": self.evaluations,
            "known": self.known,
            "file": self.path.name,
            "occurrences": self.occurrences,
            "outcome": self.outcome.to_dict(),
            "scene": self.data,
            "settlement": self.settlement.to_dict() if self.settlement else None,
        }


@dataclass(frozen=True)
class CampaignResult:
    """What a campaign found (:func:`fuzz`); ``files``: kind -> path of the files written."""

    config: FuzzConfig
    out_dir: Path
    scenes: tuple[SceneRecord, ...]
    counterexamples: tuple[Counterexample, ...]
    wall_s: float
    complete: bool
    files: dict[str, Path] = field(default_factory=dict)


__all__ = ["CampaignResult", "Counterexample", "FuzzConfig", "SceneRecord"]
