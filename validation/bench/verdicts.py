"""What a speed goal's measurement allows one to say: its spread over rounds and the verdict.

Every goal of :mod:`validation.bench.goals` is measured in rounds (both sides of the ratio timed
alternately, :func:`validation.bench.timing.interleaved`), which gives one ratio per round. The
goal's value is the median of those ratios; :class:`Spread` is their interquartile range. The
verdict (:func:`decide`) is HOLDS or FAILS only when the rounds agree well enough, by the one
bound :data:`SPREAD_BOUND`; otherwise it is TOO_BUSY: the machine was too busy for a verdict, and
the value is printed but not judged.

Pure arithmetic on measured numbers: nothing here times anything (the tests plant the timings).
"""

from __future__ import annotations

import enum
import math
import statistics
from collections.abc import Sequence
from dataclasses import dataclass


class Verdict(enum.StrEnum):
    """A goal's outcome (a ``str``: ``Verdict.HOLDS == "HOLDS"``; written as is in ``bench.json``)."""

    HOLDS = "HOLDS"
    FAILS = "FAILS"
    TOO_BUSY = "TOO_BUSY"
    """Measured, but the rounds disagree too much for a verdict (:data:`SPREAD_BOUND`)."""
    SKIPPED = "SKIPPED"
    """Not measured (a plant or the compiled loop is not installed)."""


SPREAD_BOUND = 0.2
"""The largest interquartile range of a goal's per-round ratios, as a fraction of the goal's
limit, for which ``tumble bench`` gives a verdict; above it, or when the limit lies inside that
range (a quarter or more of the rounds on the other side of it), the verdict is
:attr:`Verdict.TOO_BUSY`.

Why a fifth of the limit: timed in thread CPU time (:mod:`validation.bench.timing`), a goal's
rounds spread by a few hundredths of its limit on the 2-core machine, idle or beside one or two
CPU-bound jobs alike, and the controller-in-RK4 goals (a difference of two step costs, which
amplifies their noise about four times) by under a tenth (the figures: ``docs/performance.md``,
Speed goals' timing and verdicts). Taking the CPU away therefore leaves the rounds well inside a
fifth of the limit; a range wider than that means the machine disturbed the measurement itself,
and a ratio near its limit cannot be judged from rounds on both sides of it."""


@dataclass(frozen=True)
class Spread:
    """The distribution of a goal's per-round ratios (dimensionless, as the goal's value).

    ``low``/``high`` are the 25th/75th percentiles (linear interpolation between order statistics,
    :func:`statistics.quantiles` ``method="inclusive"``), ``median`` the 50th, over ``rounds``
    rounds. ``cpu_share`` is the median share of a CPU the measuring thread had while timed (thread
    CPU time / wall time, 1 on an idle machine, about 0.5 beside one CPU-bound job on its core), or
    None where it was not recorded."""

    low: float
    median: float
    high: float
    rounds: int
    cpu_share: float | None = None

    @property
    def width(self) -> float:
        """The interquartile range, ``high - low``."""
        return self.high - self.low

    def text(self) -> str:
        """``"interquartile 0.571-0.576 over 21 rounds"`` (+ the CPU share when recorded)."""
        s = f"interquartile {self.low:.3g}-{self.high:.3g} over {self.rounds} rounds"
        if self.cpu_share is not None:
            s += f", this thread had {self.cpu_share:.0%} of a CPU"
        return s


def spread_of(ratios: Sequence[float], cpu_share: float | None = None) -> Spread:
    """The :class:`Spread` of per-round ratios (at least one; non-finite ratios are refused).

    Raises:
        ValueError: naming ``ratios`` when it is empty or holds a NaN or an infinity.
    """
    values = [float(r) for r in ratios]
    if not values or not all(math.isfinite(v) for v in values):
        raise ValueError(f"ratios: need at least one finite per-round ratio (got {values!r})")
    if len(values) == 1:
        low = high = values[0]
    else:
        low, _, high = statistics.quantiles(values, n=4, method="inclusive")
    return Spread(low, statistics.median(values), high, len(values), cpu_share)


def decide(value: float, limit: float, spread: Spread | None = None) -> Verdict:
    """HOLDS when ``value <= limit`` and FAILS otherwise, unless ``spread`` says the rounds disagree:
    TOO_BUSY when its width exceeds ``SPREAD_BOUND * limit`` or ``low <= limit < high``. A
    non-finite value (a run failed) FAILS. Without a spread (a goal measured once) the value
    decides alone."""
    if not math.isfinite(value):
        return Verdict.FAILS
    if spread is not None and (
        spread.width > SPREAD_BOUND * limit or spread.low <= limit < spread.high
    ):
        return Verdict.TOO_BUSY
    return Verdict.HOLDS if value <= limit else Verdict.FAILS
