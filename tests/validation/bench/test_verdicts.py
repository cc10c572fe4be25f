"""The spread of a goal's per-round ratios and the verdict it allows (planted ratios: nothing is
timed here)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from validation.bench.verdicts import SPREAD_BOUND, Spread, Verdict, decide, spread_of


@pytest.mark.parametrize(
    "ratios",
    [[0.57], [0.57, 0.58], [1.0, 2.0, 3.0, 4.0, 5.0], [0.31, 0.29, 2.45, 0.30, 0.28, 0.33, 0.27]],
)
def test_spread_is_the_quartiles_of_the_ratios(ratios):
    """low/median/high are the 25th/50th/75th percentiles with linear interpolation between order
    statistics: numpy's default percentile, an independent implementation."""
    s = spread_of(ratios, cpu_share=0.5)
    expect = np.percentile(ratios, [25, 50, 75])
    assert (s.low, s.median, s.high) == pytest.approx(tuple(expect), rel=1e-12)
    assert s.rounds == len(ratios) and s.cpu_share == 0.5
    assert s.width == pytest.approx(expect[2] - expect[0], rel=1e-12, abs=1e-15)


def test_one_outlier_round_moves_neither_the_value_nor_the_spread_much():
    """The median and the quartiles ignore a round the scheduler disturbed (2.45 among ~0.3)."""
    calm = [0.27, 0.28, 0.29, 0.30, 0.31, 0.32, 0.33]
    s_calm, s_hit = spread_of(calm), spread_of([*calm[:-1], 2.45])
    assert s_hit.median == s_calm.median == 0.30
    assert s_hit.high - s_calm.high < 0.01


@pytest.mark.parametrize("bad", [[], [0.5, math.nan], [math.inf]])
def test_spread_refuses_no_or_non_finite_ratios(bad):
    with pytest.raises(ValueError, match="ratios"):
        spread_of(bad)


def _spread(low: float, high: float) -> Spread:
    return Spread(low, (low + high) / 2, high, 21)


def test_verdict_from_the_value_when_the_rounds_agree():
    assert decide(0.57, 1.0, _spread(0.56, 0.58)) is Verdict.HOLDS
    assert decide(1.0, 1.0, _spread(0.99, 1.0)) is Verdict.HOLDS  # ≤: the limit itself holds
    assert decide(1.44, 1.0, _spread(1.40, 1.48)) is Verdict.FAILS
    assert decide(0.57, 1.0) is Verdict.HOLDS and decide(1.01, 1.0) is Verdict.FAILS  # measured once


def test_too_busy_when_the_spread_is_wider_than_the_bound():
    """Width just over SPREAD_BOUND x limit: no verdict, whichever side the value is on; just under
    (and not straddling): a verdict."""
    for limit in (1.0, 1.5, 150.0):
        wide = SPREAD_BOUND * limit * 1.01
        narrow = SPREAD_BOUND * limit * 0.99
        low = 0.1 * limit
        assert decide(low + wide / 2, limit, _spread(low, low + wide)) is Verdict.TOO_BUSY
        assert decide(low + narrow / 2, limit, _spread(low, low + narrow)) is Verdict.HOLDS
        high = 2.0 * limit
        assert decide(high, limit, _spread(high, high + wide)) is Verdict.TOO_BUSY
        assert decide(high, limit, _spread(high, high + narrow)) is Verdict.FAILS


def test_too_busy_when_the_limit_lies_inside_the_spread():
    """A quarter of the rounds or more on the other side of the limit: even a narrow spread gives no
    verdict."""
    assert decide(0.98, 1.0, _spread(0.95, 1.02)) is Verdict.TOO_BUSY
    assert decide(1.02, 1.0, _spread(0.99, 1.05)) is Verdict.TOO_BUSY
    assert decide(1.02, 1.0, _spread(1.0, 1.05)) is Verdict.TOO_BUSY  # low = limit: one side holds
    assert decide(0.99, 1.0, _spread(0.95, 1.0)) is Verdict.HOLDS  # high = limit holds too


def test_a_failed_run_fails_even_with_a_spread():
    assert decide(math.inf, 1.0) is Verdict.FAILS
    assert decide(math.nan, 1.0, _spread(0.5, 0.6)) is Verdict.FAILS


def test_verdict_is_a_string_enum_with_the_documented_values():
    assert [v.value for v in Verdict] == ["HOLDS", "FAILS", "TOO_BUSY", "SKIPPED"]
    assert Verdict.HOLDS == "HOLDS" and f"{Verdict.TOO_BUSY}" == "TOO_BUSY"


def test_spread_text_names_the_quartiles_the_rounds_and_the_share():
    s = Spread(0.571, 0.574, 0.576, 21, 0.52)
    assert s.text() == "interquartile 0.571-0.576 over 21 rounds, this thread had 52% of a CPU"
    assert "CPU" not in Spread(1.0, 1.1, 1.2, 3).text()
