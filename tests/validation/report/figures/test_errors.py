"""The errors figure: the differences drawn as checked, with their thresholds."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.figure_runs import C_OFFSET, TORQUE_SCALE, controlled
from validation.report.figures import (
    FigureContext,
    figure_errors,
)


def test_errors_are_drawn_as_checked_with_their_thresholds(run):
    """The planted offset of C is the position panel's curve; the torque panel draws the relative
    difference (the planted 1e-9), at the level its check reports, under its threshold line."""
    sc, _, cmp, meta = run
    fig = figure_errors(cmp, FigureContext.from_meta(meta)).figure
    by_title = {ax.get_title(loc="left").split(":")[0]: ax for ax in fig.axes}
    pos = by_title["position of C"]
    curve, threshold = pos.lines[0].get_ydata(), pos.lines[-1].get_ydata()
    assert np.nanmax(curve) == pytest.approx(C_OFFSET, rel=1e-6)
    assert threshold[0] == cmp.thresholds["position_C"].value
    if controlled(sc):
        tq = by_title["control torque"]
        drawn = np.nanmax(tq.lines[0].get_ydata())
        assert drawn == pytest.approx(cmp.check("control_torque").value, rel=1e-12)
        assert drawn == pytest.approx(TORQUE_SCALE, rel=1e-3)
        assert tq.lines[-1].get_ydata()[0] == cmp.thresholds["control_torque"].value
