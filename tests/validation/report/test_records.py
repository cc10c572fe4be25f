"""The records a report is made of: a series summarised over time (numbers that do not mislead),
the run's verdict."""

from __future__ import annotations

import numpy as np

from validation.compare.checks import Group, Series, Subject
from validation.compare.summary import max_abs
from validation.report.records import RunVerdict, SeriesSummary


def test_max_of_a_signed_quantity_is_its_largest_magnitude():
    """A series that is mostly negative: its largest value (2) is not its largest magnitude (7)."""
    t = np.array([0.0, 0.1, 0.2, 0.3])
    s = Series(
        "analytic.rod_force_2",
        "rod force",
        "N",
        Group.CONTROL,
        Subject.ANALYTIC,
        t,
        np.array([2.0, -7.0, -3.0, -1.0]),
    )
    m = SeriesSummary.of(s)
    assert m.max_abs == 7.0 and m.t_max_abs == 0.1
    assert m.final == -1.0  # the last value keeps its sign
    assert max_abs(np.array([[3.0, 4.0], [0.0, -4.5]])) == (5.0, 0)  # vectors: Euclidean norm


def test_the_verdict_says_how_the_run_stopped():
    assert RunVerdict.of(None, "") is RunVerdict.FAILED
    assert RunVerdict.of(None, "", interrupted=True) is RunVerdict.INTERRUPTED
    assert RunVerdict.FAILED.stopped() == "failed"
    assert RunVerdict.INTERRUPTED.stopped() == "was interrupted"
