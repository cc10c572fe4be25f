"""The records a report is made of: the run's verdict (:class:`RunVerdict`), a figure as the
report lists it (:class:`FigureEntry`) and a series summarised over time (:class:`SeriesSummary`;
"max" of a quantity is always its largest magnitude, :func:`validation.compare.summary.max_abs`:
the summary of a signed rod force is its largest ``|F_i|``, not its largest value)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from validation.compare.checks import Comparison, Series
from validation.compare.summary import max_abs


class RunVerdict(StrEnum):
    """A run's verdict, the first word of ``report.md`` after the scene's name and
    ``report.json``'s ``verdict``: PASSED only when every check passed and nothing failed or was
    left out (a plant, a figure, the recording); INTERRUPTED when a signal stopped the run."""

    PASSED = "PASSED"
    FAILED = "FAILED"
    INTERRUPTED = "INTERRUPTED"

    @classmethod
    def of(cls, cmp: Comparison | None, failure: str, interrupted: bool = False) -> RunVerdict:
        if interrupted:
            return cls.INTERRUPTED
        return cls.PASSED if cmp is not None and cmp.passed and not failure else cls.FAILED

    def stopped(self) -> str:
        """How the failure line of ``report.md`` opens: ``The run failed`` / ``was interrupted``."""
        return "was interrupted" if self is RunVerdict.INTERRUPTED else "failed"


@dataclass(frozen=True)
class FigureEntry:
    """A figure as the report lists it: its name, caption, and the files written (none when it
    was not drawn; the caption then says why)."""

    name: str
    caption: str
    files: tuple[str, ...] = ()


@dataclass(frozen=True)
class SeriesSummary:
    """A series over time, summarised as the report states it.

    Attributes:
        max_abs: the largest magnitude ``max_t |x(t)|`` (for a signed rod force its largest
            ``|F_i|``; the series of vectors are already norms); ``inf`` with a non-finite sample.
        t_max_abs: the time of ``max_abs``, s.
        rms: root mean square over the samples.
        final: the last value (signed).
    """

    max_abs: float
    t_max_abs: float
    rms: float
    final: float

    @classmethod
    def of(cls, s: Series) -> SeriesSummary:
        v = np.asarray(s.values, float)
        peak, i = max_abs(v)
        if i < 0:
            return cls(math.nan, math.nan, math.nan, math.nan)
        rms = float(np.sqrt(np.mean(v * v))) if np.all(np.isfinite(v)) else math.inf
        return cls(peak, float(s.t[i]), rms, float(v[-1]))

    def to_dict(self) -> dict[str, float]:
        return {
            "max_abs": self.max_abs,
            "t_max_abs": self.t_max_abs,
            "rms": self.rms,
            "final": self.final,
        }


def summaries(cmp: Comparison | None) -> dict[str, dict[str, Any]]:
    """Series key -> label, unit and :class:`SeriesSummary` fields (report.json's ``summaries``)."""
    if cmp is None:
        return {}
    return {
        s.key: {"label": s.label, "unit": s.unit, **SeriesSummary.of(s).to_dict()}
        for s in cmp.series
    }


__all__ = ["FigureEntry", "RunVerdict", "SeriesSummary", "summaries"]
