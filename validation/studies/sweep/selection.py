"""The cheapest setting of each plant that reaches each accuracy level, and whether its timings
tell it apart from the other settings that reach the level.

The pick is the ``ok`` run of least median wall time (a ``degraded`` run is never picked). Timings
on a shared machine are noisy, so the pick is only claimed to be the cheapest when its timings
rank it: :func:`rivals` names every other candidate whose timing range (fastest to slowest) meets
the pick's, and a pick with a single timing has no measured spread at all (:func:`ranking`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from validation.studies.sweep.config import ENGINES, LEVELS, Outcome


def _candidates(runs: Sequence[Mapping[str, Any]], engine: str, level: float, floor: float):
    if level <= floor:
        return []
    return [
        r
        for r in runs
        if r["engine"] == engine
        and r["status"] == Outcome.OK
        and r["error"] is not None
        and r["wall_time_s"] is not None
        and r["error"] <= level
    ]


def cheapest_settings(
    runs: Sequence[dict[str, Any]],
    levels: Sequence[float] = LEVELS,
    floor: float = 0.0,
    engines: Sequence[str] | None = None,
) -> dict[str, dict[float, int | None]]:
    """For each engine and level, the ``ok`` run of least median wall time with error ≤ level.

    Levels at or below ``floor`` (what the reference can resolve) get None. ``engines``: the plants
    to report, in order (default: those of :data:`ENGINES` that have runs).
    """
    if engines is None:
        engines = [e for e in ENGINES if any(r["engine"] == e for r in runs)]
    out: dict[str, dict[float, int | None]] = {}
    for engine in engines:
        out[str(engine)] = {}
        for lv in levels:
            cand = _candidates(runs, str(engine), lv, floor)
            best = min(cand, key=lambda r: (r["wall_time_s"], r["run_id"]), default=None)
            out[str(engine)][lv] = None if best is None else int(best["run_id"])
    return out


def _span(r: Mapping[str, Any]) -> tuple[float, float]:
    lo = r.get("wall_time_min_s")
    hi = r.get("wall_time_max_s")
    w = r["wall_time_s"]
    return (w if lo is None else lo, w if hi is None else hi)


def rivals(
    runs: Sequence[Mapping[str, Any]], pick: int, level: float, floor: float = 0.0
) -> list[int]:
    """Run ids of the other candidates for ``level`` (same engine, ``ok``, error ≤ level) whose
    timing range [fastest, slowest] meets the pick's: the timings do not rank them."""
    by_id = {int(r["run_id"]): r for r in runs}
    p = by_id[pick]
    lo, hi = _span(p)
    out = []
    for r in _candidates(runs, str(p["engine"]), level, floor):
        if int(r["run_id"]) == pick:
            continue
        a, b = _span(r)
        if a <= hi and b >= lo:
            out.append(int(r["run_id"]))
    return sorted(out)


@dataclass(frozen=True)
class Ranking:
    """How well the timings support a pick.

    Attributes:
        timings: how many timings the pick has (1: no spread measured).
        rivals: candidates whose timing ranges meet the pick's (:func:`rivals`).
    """

    timings: int
    rivals: tuple[int, ...]

    @property
    def ranked(self) -> bool:
        """The pick is cheaper than every other candidate beyond the timings' spread."""
        return self.timings >= 2 and not self.rivals


def ranking(
    runs: Sequence[Mapping[str, Any]], pick: int, level: float, floor: float = 0.0
) -> Ranking:
    """The :class:`Ranking` of run ``pick`` as the cheapest for ``level``."""
    r = next(x for x in runs if int(x["run_id"]) == pick)
    n = int(r.get("wall_time_repeats") or 1)
    return Ranking(n, tuple(rivals(runs, pick, level, floor)))


__all__ = ["Ranking", "cheapest_settings", "ranking", "rivals"]
