"""A goal's value, spread and verdict from planted batches and spreads (the goals' timing itself is
``tumble bench``'s, never a test's)."""

from __future__ import annotations

import math

import pytest

from validation.bench.goal import Goal, round_ratios
from validation.bench.timing import Batch
from validation.bench.verdicts import SPREAD_BOUND, Spread, Verdict


def _batches(per_call_s: float, stretch: list[float], calls: int = 1000) -> list[Batch]:
    """Batches costing ``per_call_s`` of CPU per call whose wall was stretched by preemption."""
    return [Batch(calls, per_call_s * calls, per_call_s * calls * k, 3) for k in stretch]


def test_a_ratio_means_the_same_on_a_loaded_machine():
    """The busy-machine reading: the analytic side's batches stretched 3.4x in wall, MuJoCo's 1.3x.
    The per-round ratios are of thread CPU time, so they read the quiet ratio 1.33 / 2.32."""
    quiet = round_ratios(_batches(1.33e-6, [1.0] * 5), _batches(2.32e-6, [1.0] * 5))
    loaded = round_ratios(_batches(1.33e-6, [3.4] * 5), _batches(2.32e-6, [1.3] * 5))
    assert loaded == pytest.approx(quiet, rel=1e-12)
    assert quiet == pytest.approx([1.33 / 2.32] * 5, rel=1e-12)


def test_added_cost_per_round():
    """The controller-in-RK4 goal: (controlled - bare) / bare per round."""
    r = round_ratios(_batches(14.3e-6, [2.0, 1.0]), _batches(11.2e-6, [1.0, 3.0]), minus_one=True)
    assert r == pytest.approx([14.3 / 11.2 - 1] * 2, rel=1e-12)


def test_goal_verdict_follows_its_spread():
    tight = Spread(0.56, 0.57, 0.58, 21, 0.5)
    g = Goal("evaluation n=2", 0.57, 1.0, "d", spread=tight)
    assert g.verdict is Verdict.HOLDS and g.holds
    assert "interquartile 0.56-0.58 over 21 rounds" in g.line() and ": holds." in g.line()
    wide = Spread(0.3, 0.6, 0.3 + SPREAD_BOUND * 1.5, 21, 0.3)
    busy = Goal("evaluation n=2", 0.6, 1.0, "d", spread=wide)
    assert busy.verdict is Verdict.TOO_BUSY and not busy.holds
    assert "the machine was too busy for a verdict" in busy.line()
    assert Goal("x", 1.2, 1.0, spread=Spread(1.19, 1.2, 1.21, 5)).verdict is Verdict.FAILS


def test_skipped_and_unmeasured_goals():
    skipped = Goal("p", math.nan, 3.0, skipped="pin is not installed")
    assert skipped.verdict is Verdict.SKIPPED and not skipped.holds
    assert skipped.line() == "p: skipped (pin is not installed)"
    assert Goal("x", math.inf, 1.0, "a run failed").verdict is Verdict.FAILS
