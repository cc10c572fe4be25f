"""The records of a validation: what it returns (:class:`ValidationResult`) and the runs made
elsewhere that join its plants' (:class:`JoinedRuns`)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from analytic.trajectory import Trajectory
from validation.compare.checks import Check, Comparison
from validation.compare.referee import Verdict


@dataclass(frozen=True)
class ValidationResult:
    """The outcome of :func:`run_validation`.

    Attributes:
        scene: scene name.
        out_dir: where the files are.
        passed: every check passed, nothing failed, and every file of ``files`` is whole in
            ``out_dir`` (the report's verdict is PASSED).
        checks: every check (empty if no comparison could be made).
        comparison: the comparison (None if no analytic trajectory exists).
        failure: why the run failed ("" if it did not).
        files: name -> path of every file written.
        wall_times: stage -> seconds (each plant, compare, report, recording, total).
        verdicts: the referee's rulings (three plants), see :mod:`validation.compare.referee`.
    """

    scene: str
    out_dir: Path
    passed: bool
    checks: tuple[Check, ...]
    comparison: Comparison | None
    failure: str = ""
    files: dict[str, Path] = field(default_factory=dict)
    wall_times: dict[str, float] = field(default_factory=dict)
    verdicts: tuple[Verdict, ...] = ()

    @property
    def failed_checks(self) -> tuple[Check, ...]:
        return tuple(c for c in self.checks if not c.passed)


@dataclass(frozen=True)
class JoinedRuns:
    """Runs made elsewhere that join the plants' results as more plants (:mod:`validation.external`:
    another engine's trajectory file, a reference pack's trajectory): compared, refereed,
    reported, drawn and recorded as the plants are.

    Attributes:
        trajectories: each a complete run of the request's scene on its output grid, its
            ``engine`` a plant name of its own (none of the running plants'), in report order
            after the plants that run.
        names: plant name -> how the report and the referee's sentences name it.
        amend: applied to the comparison before the referee rules (the judge marks the checks a
            file cannot support "not judged"); None: the comparison as made.
        meta: more entries of the report's run metadata (where each joined run came from).
    """

    trajectories: tuple[Trajectory, ...] = ()
    names: Mapping[str, str] = field(default_factory=dict)
    amend: Callable[[Comparison], Comparison] | None = None
    meta: Mapping[str, Any] = field(default_factory=dict)


NO_JOINED = JoinedRuns()
"""No run joins: :func:`run_validation`'s plants alone."""


__all__ = ["NO_JOINED", "JoinedRuns", "ValidationResult"]
