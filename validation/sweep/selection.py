"""The cheapest setting of each plant that reaches each accuracy level."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from validation.sweep.config import ENGINES, LEVELS, Outcome


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
        ok = [
            r
            for r in runs
            if r["engine"] == engine
            and r["status"] == Outcome.OK
            and r["error"] is not None
            and r["wall_time_s"] is not None
        ]
        out[str(engine)] = {}
        for lv in levels:
            cand = [r for r in ok if r["error"] <= lv] if lv > floor else []
            best = min(cand, key=lambda r: (r["wall_time_s"], r["run_id"]), default=None)
            out[str(engine)][lv] = None if best is None else int(best["run_id"])
    return out


__all__ = ["cheapest_settings"]
