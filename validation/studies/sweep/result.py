"""What a sweep found: the record :func:`validation.studies.sweep.run_sweep` returns and the files are
written from."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any


@dataclass(frozen=True)
class SweepResult:
    """The outcome of :func:`validation.studies.sweep.run_sweep`.

    Attributes:
        scene: the scene's name.
        out_dir: where the files are.
        config: the grid and limits used (:class:`~validation.studies.sweep.config.SweepConfig` as a dict).
        reference: how the reference was computed (or that it came from the cache), its cost and
            estimated error.
        runs: one row per setting (keys :data:`~validation.studies.sweep.rows.COLUMNS`), in grid order.
        cheapest: ``{engine: {level: run_id or None}}``, the cheapest run (median wall time) whose
            error is at most the level, for every plant that ran.
        stabilization: rows of the (δ1, δ2) study.
        effects: rows of the per-evaluation cost with each effect off.
        skipped_series: ``{engine: reason}`` for the plants whose series were not run (Pinocchio
            when ``pin`` is not installed).
        series: ``(engine, method)`` of every series, in grid order.
        workers: how many runs the executor ran at once (None: the user's executor).
        files: name -> path of every file written.
        wall_time_s: the whole sweep; stage_wall_s: its stages.
    """

    scene: str
    out_dir: Path
    config: Mapping[str, Any]
    reference: Mapping[str, Any]
    runs: tuple[dict[str, Any], ...]
    cheapest: Mapping[str, Mapping[float, int | None]]
    stabilization: tuple[Mapping[str, Any], ...]
    effects: tuple[Mapping[str, Any], ...]
    skipped_series: Mapping[str, str] = field(default_factory=dict)
    series: tuple[tuple[str, str], ...] = ()
    workers: int | None = None
    files: Mapping[str, Path] = field(default_factory=dict)
    wall_time_s: float = 0.0
    stage_wall_s: Mapping[str, float] = field(default_factory=dict)

    def run(self, run_id: int) -> Mapping[str, Any]:
        return self.runs[run_id]


__all__ = ["SweepResult"]
