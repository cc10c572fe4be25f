"""A speed goal's record (:class:`Goal`: a measured ratio against its limit, its spread over the
rounds and its verdict) and the ratios the goals take of their rounds."""

from __future__ import annotations

import statistics
from dataclasses import dataclass, field
from typing import Any

from validation.bench.verdicts import Spread, Verdict, decide


@dataclass(frozen=True)
class Goal:
    """One goal: ``value`` compared with ``limit`` (holds when value ≤ limit and, when measured
    in rounds, the rounds agree: :func:`validation.bench.verdicts.decide`)."""

    name: str
    value: float
    limit: float
    detail: str = ""
    extrapolated: bool = False
    data: dict[str, Any] = field(default_factory=dict)
    skipped: str = ""
    """Why the goal was not measured ("" when it was); a skipped goal neither holds nor fails."""
    spread: Spread | None = None
    """The per-round ratios' spread (None: measured once)."""

    @property
    def verdict(self) -> Verdict:
        """HOLDS, FAILS, TOO_BUSY or SKIPPED."""
        if self.skipped:
            return Verdict.SKIPPED
        return decide(self.value, self.limit, self.spread)

    @property
    def holds(self) -> bool:
        return self.verdict is Verdict.HOLDS

    def line(self) -> str:
        if self.skipped:
            return f"{self.name}: skipped ({self.skipped})"
        verdict = {
            Verdict.HOLDS: "holds",
            Verdict.FAILS: "fails",
            Verdict.TOO_BUSY: "the machine was too busy for a verdict (the rounds disagree)",
        }[self.verdict]
        if self.extrapolated:
            verdict += " (extrapolated)"
        spread = f"; {self.spread.text()}" if self.spread else ""
        return (
            f"{self.name}: ratio {self.value:.3g} (goal ≤ {self.limit:g}{spread}): {verdict}. "
            f"{self.detail}"
        )


def round_ratios(num: list, den: list, minus_one: bool = False) -> list[float]:
    """Per-round ratios of two functions' batches (thread CPU per call); ``minus_one``: the added
    cost ``num / den - 1``."""
    return [
        a.per_call_s / b.per_call_s - (1.0 if minus_one else 0.0)
        for a, b in zip(num, den, strict=True)
    ]


def run_share(cpus: dict[str, list[float]], walls: dict[str, list[float]]) -> float | None:
    """Median share of a CPU over whole runs (CPU time / wall of each), None without runs."""
    shares = [c / w for k in cpus for c, w in zip(cpus[k], walls[k], strict=True) if w > 0]
    return statistics.median(shares) if shares else None


__all__ = ["Goal", "round_ratios", "run_share"]
