"""The invariants figure: the balances drawn relative, as checked, with their thresholds."""

from __future__ import annotations

import numpy as np
import pytest

from validation.report.figures import (
    FigureContext,
    figure_invariants,
)


def test_invariants_are_drawn_relative_with_their_thresholds(run):
    """Each relative balance is drawn divided by its scale: the curve's maximum is the check's
    value, and the threshold line is the relative threshold of validation/compare/thresholds.py."""
    _, _, cmp, meta = run
    fig = figure_invariants(cmp, FigureContext.from_meta(meta)).figure
    names = ("quat_norm", "linear_momentum", "angular_momentum", "energy")
    assert len(fig.axes) == len(names)
    for ax, name in zip(fig.axes, names, strict=True):
        check = cmp.check(f"analytic.{name}")
        th = cmp.thresholds[name]
        assert th.relative == (name != "quat_norm")
        assert np.nanmax(ax.lines[0].get_ydata()) == pytest.approx(check.value, rel=1e-12)
        assert ax.lines[-1].get_ydata()[0] == th.value
        assert ("relative" in ax.get_ylabel()) == th.relative
